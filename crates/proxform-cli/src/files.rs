//! The binary's boundary with the file system: reading the files a user names (regular files
//! only, of bounded size) and naming the output folders (inside `out/`, whatever a name says).

use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Largest scenario or comparison file read (bytes). A file that size already describes
/// hundreds of thousands of slots, waypoints or faults.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// Most worker threads: more than the cores only costs memory and time.
pub const MAX_THREADS: usize = 256;

/// The text of the file at `path` (`what` names it in errors): a regular file of at most
/// [`MAX_INPUT_BYTES`] in UTF-8. A FIFO, a device or a folder is refused before anything is
/// read from it, so nothing blocks or fills memory.
pub fn read_input(path: &Path, what: &str) -> Result<String> {
    let meta = std::fs::metadata(path).with_context(|| format!("cannot read {what} {}", path.display()))?;
    if !meta.is_file() {
        bail!("{what} {} is not a regular file", path.display());
    }
    if meta.len() > MAX_INPUT_BYTES {
        bail!(
            "{what} {} is {} MiB, more than the {} MiB a {what} may have",
            path.display(),
            meta.len() >> 20,
            MAX_INPUT_BYTES >> 20
        );
    }
    let file = std::fs::File::open(path).with_context(|| format!("cannot read {what} {}", path.display()))?;
    let mut text = String::new();
    // The size may change between the check and the read: never read more than the cap.
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_string(&mut text)
        .with_context(|| format!("cannot read {what} {} as UTF-8 text", path.display()))?;
    if text.len() as u64 > MAX_INPUT_BYTES {
        bail!("{what} {} grew past {} MiB while being read", path.display(), MAX_INPUT_BYTES >> 20);
    }
    Ok(text)
}

/// The default output folder of a run or comparison named `name`: `out/<name>`, the name
/// reduced to letters, digits, `-`, `_` and `.` (others become `_`, leading dots are dropped),
/// so that no name leaves `out/` (`../x`, `/etc`, `C:\`).
pub fn default_out(name: &str) -> PathBuf {
    let mut safe: String =
        name.chars().map(|c| if c.is_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' }).collect();
    safe = safe.trim_start_matches('.').chars().take(100).collect();
    if safe.is_empty() {
        safe = "unnamed".into();
    }
    PathBuf::from("out").join(safe)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_stay_inside_out() {
        for name in ["../../x", "/etc/passwd", "..", "a/../../b", "C:\\temp", "", "...", "ok-name_1.2"] {
            let p = default_out(name);
            assert_eq!(p.components().count(), 2, "{name} → {}", p.display());
            assert!(p.starts_with("out"), "{name} → {}", p.display());
            assert!(!p.file_name().is_some_and(|f| f.to_string_lossy().starts_with('.')), "{name}");
        }
        assert_eq!(default_out("ok-name_1.2"), PathBuf::from("out/ok-name_1.2"));
        assert_eq!(default_out("paper / proximity / ideal"), PathBuf::from("out/paper___proximity___ideal"));
    }
}
