//! The CLI's integration tests, one module per topic (the older `tests/*.rs` files are being
//! folded in here).

mod collapse;
