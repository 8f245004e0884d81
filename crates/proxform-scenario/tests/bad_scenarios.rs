//! Every invalid scenario gets a located, named error.
//!
//! `tests/bad/*.toml` each start with `# expect: TEXT` (a part of the message) and optionally
//! `# line: N` (the line the error must point at; `none` for a key missing from the file).

use std::path::Path;

use proxform_scenario::load::parse;

fn header(text: &str, tag: &str) -> Option<String> {
    text.lines().find_map(|l| l.strip_prefix(tag).map(|v| v.trim().to_string()))
}

#[test]
fn every_bad_scenario_is_refused_with_a_located_message() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad");
    let mut files: Vec<_> = std::fs::read_dir(&dir).expect("tests/bad").map(|e| e.expect("entry").path()).collect();
    files.sort();
    assert!(files.len() >= 30, "only {} bad scenarios", files.len());
    for path in files {
        let text = std::fs::read_to_string(&path).expect("readable");
        let name = path.file_name().and_then(|n| n.to_str()).expect("name").to_string();
        let expect = header(&text, "# expect:").unwrap_or_else(|| panic!("{name}: no '# expect:' line"));
        let e = match parse(&text, &name) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => e,
        };
        let msg = e.to_string();
        assert!(msg.starts_with(&name), "{name}: message does not name the file: {msg}");
        assert!(msg.contains(&expect), "{name}: expected «{expect}» in «{msg}»");
        match header(&text, "# line:").as_deref() {
            // A key missing from the whole file has no line to point at.
            Some("none") => assert_eq!(e.line, None, "{name}: «{msg}»"),
            Some(line) => assert_eq!(e.line, line.parse().ok(), "{name}: wrong line in «{msg}»"),
            None => assert!(e.line.is_some(), "{name}: no line in «{msg}»"),
        }
    }
}
