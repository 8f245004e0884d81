//! The loader never panics on mutated scenario files, and whatever it accepts flies.

use std::path::Path;

use proxform_scenario::load::parse;
use proxform_scenario::Scenario;
use proxform_sim::{RunMetrics, RunOptions, Simulation};

/// A small deterministic generator for the mutation test.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0 >> 17
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn mutate(text: &str, rng: &mut Lcg) -> String {
    let mut s: Vec<char> = text.chars().collect();
    const VALUES: [&str; 12] =
        ["nan", "inf", "-inf", "0", "-1", "1e308", "-1e308", "1e-300", "4294967295", "\"x\"", "[]", "{}"];
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(s.len());
        match rng.below(5) {
            0 => {
                let end = (at + rng.below(20)).min(s.len());
                s.drain(at..end);
            }
            1 => {
                const CHARS: &[u8] = b"=[]{}\",.#\n 0123456789-eabcxyz_";
                let c = CHARS[rng.below(CHARS.len())] as char;
                s.insert(at, c);
            }
            2 => {
                // Replace the number that follows an '=' with an extreme value.
                if let Some(eq) = s[at..].iter().position(|c| *c == '=') {
                    let start = at + eq + 1;
                    let end = s[start..].iter().position(|c| *c == '\n').map_or(s.len(), |p| start + p);
                    let v: Vec<char> = format!(" {}", VALUES[rng.below(VALUES.len())]).chars().collect();
                    s.splice(start..end, v);
                }
            }
            3 => {
                let line_start = s[..at].iter().rposition(|c| *c == '\n').map_or(0, |p| p + 1);
                let line_end = s[at..].iter().position(|c| *c == '\n').map_or(s.len(), |p| at + p);
                let line: Vec<char> = s[line_start..line_end].to_vec();
                s.splice(line_end..line_end, std::iter::once('\n').chain(line));
            }
            _ => s.truncate(at),
        }
    }
    s.into_iter().collect()
}

#[test]
fn the_loader_never_panics_on_mutated_scenarios() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut sources = Vec::new();
    for e in std::fs::read_dir(&root).expect("scenarios/") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "toml") {
            sources.push(std::fs::read_to_string(&p).expect("readable"));
        }
    }
    let mut rng = Lcg(0x5EED);
    let (mut ok, mut refused) = (0, 0);
    for k in 0..4000 {
        let text = mutate(&sources[k % sources.len()], &mut rng);
        match parse(&text, "mutant.toml") {
            Ok(s) if s.len() <= 200 && (s.dt_s() * 3.0).is_finite() => {
                // A scenario that loads must also fly a few steps without panicking.
                let short = s.spec().clone().with(|x| x.duration_s = Some(s.dt_s() * 3.0));
                let s = Scenario::try_from(short).expect("a loaded scenario stays valid when shortened");
                let sim = Simulation::new(&s, RunOptions::default(), 1, 0);
                let mut m = RunMetrics::new(&s);
                sim.run(&mut m);
                ok += 1;
            }
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(!e.message.is_empty());
                refused += 1;
            }
        }
    }
    assert!(ok > 100 && refused > 100, "mutations too mild or too harsh: {ok} loaded, {refused} refused");
}

#[test]
fn comparison_files_never_panic_when_mutated_and_what_loads_has_valid_cells() {
    use proxform_scenario::builtin::{paper_spec, COMPARE_PAPER};
    use proxform_scenario::comparison::Comparison;
    let mut rng = Lcg(0xC0FFEE);
    let (mut ok, mut refused) = (0, 0);
    for _ in 0..3000 {
        let text = mutate(COMPARE_PAPER, &mut rng);
        match Comparison::parse(&text, "mutant.toml", |name| match name {
            "paper" => Ok(paper_spec()),
            other => Err(format!("unknown scenario '{other}'")),
        }) {
            Ok(c) => {
                // Every cell of an accepted comparison is a valid scenario, within the bounds.
                assert!(c.seeds >= 1 && c.runs() <= proxform_scenario::comparison::MAX_RUNS);
                for m in &c.methods {
                    for cond in &c.conditions {
                        cond.scenario(&c.base_spec, m).expect("a checked comparison's cells are valid");
                    }
                }
                ok += 1;
            }
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.starts_with("mutant.toml") || msg.starts_with("condition"), "unlocated: {msg}");
                refused += 1;
            }
        }
    }
    assert!(ok > 100 && refused > 100, "mutations too mild or too harsh: {ok} loaded, {refused} refused");
}
