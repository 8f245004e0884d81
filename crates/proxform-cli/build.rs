//! The commit the binary is built from (`PROXFORM_COMMIT`, "unknown" outside a git checkout),
//! for the outputs that say what made them (`scenario.toml`'s header).

use std::process::Command;

fn main() {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok())
            .map(|s| s.trim().to_string())
    };
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=PROXFORM_COMMIT={commit}");
    // Built again when HEAD moves (a new commit on the branch, or another branch).
    // (Only files that exist: cargo runs the script every build for one that does not.)
    if let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) {
        let head = git(&["symbolic-ref", "-q", "HEAD"]);
        let files = ["HEAD".to_string(), head.unwrap_or_default(), "packed-refs".into()];
        for f in files.iter().filter(|f| !f.is_empty()) {
            let path = std::path::Path::new(&dir).join(f);
            if path.is_file() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    println!("cargo:rerun-if-changed=build.rs");
}
