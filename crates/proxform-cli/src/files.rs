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
            "{what} {} is {} bytes, more than the {} bytes ({} MiB) a {what} may have",
            path.display(),
            meta.len(),
            MAX_INPUT_BYTES,
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

/// Makes way for an output file at `path`: an existing regular file is removed (the output is
/// written fresh), nothing there is fine; a symbolic link, FIFO, device or folder there is
/// refused before anything is opened, so no output is written through a link to elsewhere and
/// nothing blocks on a FIFO.
pub fn clear_output(path: &Path) -> Result<()> {
    check_output(path)?;
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot replace {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// Refuses, before anything flies, an output path a link, FIFO, device or folder took; a
/// regular file there is left as it is (replaced only when the new one is written).
pub fn check_output(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            bail!("{} is a symbolic link: outputs are not written through links (remove it)", path.display())
        }
        Ok(m) if !m.is_file() => bail!("{} exists and is not a regular file: it cannot be an output", path.display()),
        _ => Ok(()),
    }
}

/// Creates the output file at `path` fresh (see [`clear_output`]); never follows a link or
/// opens what another process put there meanwhile.
pub fn create_output(path: &Path) -> Result<std::fs::File> {
    clear_output(path)?;
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .with_context(|| format!("cannot create {}", path.display()))
}

/// `path` itself once cleared for a writer that opens it (a figure backend).
pub fn fresh(path: &Path) -> Result<&Path> {
    clear_output(path)?;
    Ok(path)
}

/// An output folder held by this process alone while the value lives (an advisory lock on the
/// folder itself, released when dropped or when the process dies, however it dies): a second
/// `proxform` writing the same folder (a requeued job with `--resume`) is refused at once
/// instead of interleaving two journals.
pub struct FolderLock {
    _dir: std::fs::File,
}

/// Takes `dir`'s lock, or says who has it.
pub fn lock_folder(dir: &Path) -> Result<FolderLock> {
    let f = std::fs::File::open(dir).with_context(|| format!("cannot open the folder {}", dir.display()))?;
    match f.try_lock() {
        Ok(()) => Ok(FolderLock { _dir: f }),
        Err(std::fs::TryLockError::WouldBlock) => bail!(
            "{} is being written by another proxform process: wait for it to end, or give another --out",
            dir.display()
        ),
        Err(std::fs::TryLockError::Error(e)) => {
            Err(e).with_context(|| format!("cannot lock the folder {}", dir.display()))
        }
    }
}

/// A command's output folder, made (with its parents) when it was not there. A folder this
/// command made and left empty (it failed before writing anything: a refused merge, a
/// scenario refused after the folder was made) is removed again when the value is dropped, so
/// that an error leaves nothing behind; one that was there, or holds anything, is left.
pub struct OutputFolder {
    path: PathBuf,
    made: bool,
}

impl OutputFolder {
    /// Makes `path` if needed; `what` names it in errors.
    pub fn new(path: &Path, what: &str) -> Result<Self> {
        let made = !path.exists();
        std::fs::create_dir_all(path).with_context(|| format!("cannot create {what} {}", path.display()))?;
        Ok(Self { path: path.to_path_buf(), made })
    }
}

impl Drop for OutputFolder {
    fn drop(&mut self) {
        if self.made {
            // Removes an empty folder only.
            let _ = std::fs::remove_dir(&self.path);
        }
    }
}

/// A folder of this process's own in the temporary folder, readable by its owner only (0700),
/// made fresh (never one that was there: a name another user planted is passed over) and removed
/// with all it holds when dropped: on every return and error, and on Ctrl-C, which ends the
/// run by returning.
pub struct PrivateTemp {
    dir: PathBuf,
}

impl PrivateTemp {
    /// Makes the folder; `what` starts its name.
    pub fn new(what: &str) -> Result<Self> {
        use std::os::unix::fs::DirBuilderExt;
        let base = std::env::temp_dir();
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let mut last = None;
        for k in 0..64u32 {
            let dir = base.join(format!("{what}-{}-{nanos:08x}-{k}", std::process::id()));
            // mkdir never follows a link at its last component and fails on anything there.
            match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
                Ok(()) => return Ok(Self { dir }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
                Err(e) => return Err(e).with_context(|| format!("cannot make a private folder in {}", base.display())),
            }
        }
        Err(last.map_or_else(|| anyhow::anyhow!("no name left"), anyhow::Error::from))
            .with_context(|| format!("cannot make a private folder in {}", base.display()))
    }

    /// Writes `text` to a new file `name` inside the folder and returns its path.
    pub fn write(&self, name: &str, text: &str) -> Result<PathBuf> {
        let path = self.dir.join(name);
        std::io::Write::write_all(&mut create_output(&path)?, text.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }
}

impl Drop for PrivateTemp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
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
    fn outputs_are_written_fresh_never_through_links_or_fifos() {
        let dir = std::env::temp_dir().join(format!("proxform-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        let target = dir.join("elsewhere.txt");
        std::fs::write(&target, "keep").expect("write");
        let link = dir.join("summary.json");
        std::os::unix::fs::symlink(&target, &link).expect("symlink");
        let e = create_output(&link).expect_err("a link");
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read_to_string(&target).expect("read"), "keep");
        let old = dir.join("old.csv");
        std::fs::write(&old, "old").expect("write");
        use std::io::Write;
        create_output(&old).expect("replaced").write_all(b"new").expect("write");
        assert_eq!(std::fs::read_to_string(&old).expect("read"), "new");
        let e = create_output(&dir).expect_err("a folder");
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn private_temporary_folders_are_the_owners_fresh_and_removed() {
        use std::os::unix::fs::PermissionsExt;
        let a = PrivateTemp::new("proxform-test").expect("folder");
        let b = PrivateTemp::new("proxform-test").expect("another");
        assert_ne!(a.dir, b.dir);
        let mode = std::fs::metadata(&a.dir).expect("meta").permissions().mode();
        assert_eq!(mode & 0o777, 0o700);
        let f = a.write("s.toml", "x = 1").expect("write");
        assert_eq!(std::fs::read_to_string(&f).expect("read"), "x = 1");
        assert!(a.write("s.toml", "again").is_ok(), "a file of its own is replaced");
        let dir = a.dir.clone();
        drop(a);
        assert!(!dir.exists(), "removed with what it holds");
    }

    #[test]
    fn an_output_folder_is_one_writers_at_a_time() {
        let dir = std::env::temp_dir().join(format!("proxform-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("folder");
        let held = lock_folder(&dir).expect("free");
        let e = lock_folder(&dir).err().expect("held");
        assert!(e.to_string().contains("another proxform process"), "{e}");
        drop(held);
        assert!(lock_folder(&dir).is_ok(), "released when dropped");
        let _ = std::fs::remove_dir_all(&dir);
    }

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
