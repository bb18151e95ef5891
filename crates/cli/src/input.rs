//! Reading the user's input files. A file that cannot be read (missing, a directory, no
//! permission) or is not UTF-8 text is a bad input (exit status 2, README), not an I/O failure
//! of Kappe's (3): the user has to fix the path or the file.

use std::path::Path;

use crate::exit::Usage;

/// The text of the input file `path`; `what` names it in the error ("design file", …).
pub fn read_text(path: &Path, what: &str) -> Result<String, Usage> {
    std::fs::read_to_string(path).map_err(|e| {
        let p = path.display();
        Usage(match e.kind() {
            std::io::ErrorKind::NotFound => format!("cannot read the {what} {p}: no such file"),
            std::io::ErrorKind::InvalidData => {
                format!("cannot read the {what} {p}: it is not UTF-8 text (a binary file?)")
            }
            std::io::ErrorKind::IsADirectory => {
                format!("cannot read the {what} {p}: it is a directory, not a file")
            }
            std::io::ErrorKind::PermissionDenied => {
                format!("cannot read the {what} {p}: permission denied")
            }
            _ => format!("cannot read the {what} {p}: {e}"),
        })
    })
}
