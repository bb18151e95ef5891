//! The CLI's integration tests, one binary (a module per topic).

mod designer;
