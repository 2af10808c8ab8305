//! Outputs that would replace one of the command's own inputs are refused before anything is
//! written: a render over its scene's texture, a conversion over its source, a heat map over the
//! reference it was measured against, a merge over one of its pieces.

use anyhow::Result;
use std::path::{Path, PathBuf};

/// A usage error (exit status 2) if `output` is the same file as one of `inputs`, whatever the
/// paths' spelling or links (both resolved): `flag` names the option that gave `output`, and
/// `what` says what the inputs are ("one of the pieces to merge"). An output that does not exist
/// yet is no input.
pub fn refuse_replacing_an_input(
    flag: &str,
    output: &Path,
    inputs: &[PathBuf],
    what: &str,
) -> Result<()> {
    let Ok(out) = std::fs::canonicalize(output) else {
        return Ok(());
    };
    match inputs
        .iter()
        .find(|input| std::fs::canonicalize(input).is_ok_and(|p| p == out))
    {
        Some(input) if input.as_path() == output => Err(crate::StatusError::usage(format!(
            "{flag} {} is {what}; name another output",
            output.display()
        ))
        .into()),
        Some(input) => Err(crate::StatusError::usage(format!(
            "{flag} {} is {what} ({}); name another output",
            output.display(),
            input.display()
        ))
        .into()),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_input_under_any_spelling_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("ref.png");
        std::fs::write(&input, b"x").unwrap();
        let inputs = [input.clone()];
        // The same path, another spelling, and a link to it.
        let spelled = dir.path().join(".").join("ref.png");
        let link = dir.path().join("link.png");
        #[cfg(unix)]
        std::os::unix::fs::symlink(&input, &link).unwrap();
        for output in [&input, &spelled, &link] {
            if !output.exists() {
                continue;
            }
            let e = refuse_replacing_an_input("--diff", output, &inputs, "an input").unwrap_err();
            let status = e.downcast_ref::<crate::StatusError>().unwrap();
            assert_eq!(status.status, 2, "{e}");
            assert!(e.to_string().contains("name another output"), "{e}");
        }
        // Another file, and one not there yet, are no input.
        let other = dir.path().join("other.png");
        refuse_replacing_an_input("--diff", &other, &inputs, "an input").unwrap();
        std::fs::write(&other, b"y").unwrap();
        refuse_replacing_an_input("--diff", &other, &inputs, "an input").unwrap();
    }
}
