//! Checks on output paths, made before any work starts: the output is not
//! an existing directory, its directory exists, and it is not one of the
//! command's input files (compared by device and inode, so hard links,
//! symbolic links and `./x.ply` spellings are caught). Every command that
//! writes a file from input files calls [`check_output`].

use anyhow::{bail, Result};
use std::path::Path;

/// Refuses `output` when it is a directory, when its directory does not
/// exist, or when it is the same file as one of `inputs` (which would be
/// replaced: "OUT: is the same file as the input IN; write to another
/// path").
pub fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    if output.is_dir() {
        bail!("{}: is a directory; give the output a file name", output.display());
    }
    let parent = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        bail!("{}: the output's directory {} does not exist", output.display(), parent.display());
    }
    check_not_input(output, inputs)
}

/// Refuses `output` when it is the same file as one of `inputs` (nothing
/// else: for files a command writes inside a directory it creates).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    let Ok(out) = std::fs::metadata(output) else { return Ok(()) };
    for input in inputs {
        if let Ok(inp) = std::fs::metadata(input) {
            if same_file(&out, &inp) {
                bail!("{}: is the same file as the input {}; write to another path", output.display(), input.display());
            }
        }
    }
    Ok(())
}

#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_file(_a: &std::fs::Metadata, _b: &std::fs::Metadata) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_that_are_inputs_directories_or_homeless_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a.ply");
        std::fs::write(&a, "x").unwrap();
        let link = d.path().join("hard.ply");
        std::fs::hard_link(&a, &link).unwrap();
        let e = check_output(&link, &[&a]).unwrap_err().to_string();
        assert!(e.contains("is the same file as the input") && e.contains("a.ply"), "{e}");
        let dotted = d.path().join(".").join("a.ply");
        assert!(check_output(&dotted, &[&a]).is_err());
        assert!(check_output(&d.path().join("b.ply"), &[&a]).is_ok());
        let e = check_output(d.path(), &[&a]).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        let e = check_output(&d.path().join("no/such/dir/o.ply"), &[&a]).unwrap_err().to_string();
        assert!(e.contains("does not exist"), "{e}");
    }
}
