//! N agent steps of one variant of the robust settings, for instruction counts under
//! callgrind (`scripts/callgrind-agent.sh`): `agent_steps VARIANT N`.

#[path = "../benches/support/mod.rs"]
mod support;

use support::variants;

fn main() {
    let mut args = std::env::args().skip(1);
    let variant = args.next().unwrap_or_else(|| "paper".into());
    let n: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000);
    assert!(variants::VARIANTS.contains(&variant.as_str()), "variants: {:?}", variants::VARIANTS);
    let mut flight = variants::Flight::new(&variant);
    let mut adjusted = 0u64;
    for _ in 0..n {
        adjusted += u64::from(matches!(flight.step().outcome, proxform_core::Outcome::Adjusted { .. }));
    }
    println!("{variant}: {n} steps, {adjusted} adjusted");
}
