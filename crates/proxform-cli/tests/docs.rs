//! The documents as a reader follows them: every link of the README and of docs/ resolves
//! inside the repository (the file, and the heading it names), and the README stays an entry
//! point (at most 300 lines).

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repository")
}

/// GitHub's anchor of a heading: lower case, spaces to dashes, punctuation dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        if !fenced && line.starts_with('#') {
            out.push(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// The targets of the Markdown links `[text](target)` of `text`, outside code.
fn links(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Inline code spans hold no links.
        let plain: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let mut rest = plain.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            out.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    out
}

#[test]
fn every_document_link_resolves_inside_the_repository() {
    let root = root();
    let mut docs = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).expect("docs/") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "md") {
            docs.push(p);
        }
    }
    let mut bad = Vec::new();
    let mut checked = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(doc).expect("readable");
        for target in links(&text) {
            if target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:") {
                bad.push(format!("{}: {target} leaves the repository", doc.display()));
                continue;
            }
            let (file, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let file = if file.is_empty() { doc.clone() } else { doc.parent().expect("folder").join(file) };
            checked += 1;
            if !file.exists() {
                bad.push(format!("{}: {target}: no such file", doc.display()));
                continue;
            }
            if !anchor.is_empty() && file.extension().is_some_and(|x| x == "md") {
                let there = std::fs::read_to_string(&file).expect("readable");
                if !anchors(&there).iter().any(|a| a == anchor) {
                    bad.push(format!("{}: {target}: no such heading", doc.display()));
                }
            }
        }
    }
    assert!(checked > 20, "only {checked} links found: the scan is broken");
    assert!(bad.is_empty(), "{} bad link(s):\n{}", bad.len(), bad.join("\n"));
}

#[test]
fn the_readme_is_an_entry_point() {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = text.lines().count();
    assert!(lines <= 300, "README.md has {lines} lines (at most 300: the rest belongs in docs/)");
}

#[test]
fn headings_make_githubs_anchors() {
    assert_eq!(slug(" What `proxform run` does"), "what-proxform-run-does");
    assert_eq!(slug(" From the paper's symbols to the code"), "from-the-papers-symbols-to-the-code");
    assert_eq!(links("see [a](docs/x.md#y) and `[no](z)`"), vec!["docs/x.md#y".to_string()]);
}
