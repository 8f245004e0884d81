//! The printed report: per-follower errors against the allowable ones, and the batch summary.

use std::time::Duration;

use proxform_sim::{BatchResult, Scenario};

const AXES: [&str; 6] = ["x m", "y m", "z m", "α °", "β °", "γ °"];

/// Prints the table of one batch.
pub fn print(scenario: &Scenario, result: &BatchResult, elapsed: Duration, threads: usize) {
    let s = &result.summary;
    let allow = s.allowable_error.as_array();
    println!(
        "proxform run: scenario '{}', {} run(s) from seed {}, {:.2} s on {} thread(s)\n",
        s.scenario,
        s.runs,
        s.seed,
        elapsed.as_secs_f64(),
        threads
    );
    println!("Largest |error| relative to the navigator (METHOD §7), over all runs:");
    print!("{:<8}", "UAV");
    for a in AXES {
        print!("{a:>10}");
    }
    println!("{:>14}{:>8}", "adjust/run", "result");
    print!("{:<8}", "allowed");
    for a in allow {
        print!("{a:>10.3}");
    }
    println!();
    let nav = scenario.navigator.index();
    let followers = (0..scenario.len()).filter(|&i| i != nav);
    for (f, i) in followers.enumerate() {
        let w = s.per_uav_worst[f].as_array();
        let ok = w.iter().zip(&allow).all(|(e, a)| e <= a);
        print!("{:<8}", format!("UAV{}", i + 1));
        for e in w {
            print!("{e:>10.3}");
        }
        println!("{:>14.1}{:>8}", s.per_uav_adjustments[f], if ok { "PASS" } else { "FAIL" });
    }
    println!();
    row("p99 over runs", &s.p99_abs_error.as_array());
    row("median", &s.median_abs_error.as_array());
    row("RMS measured", &s.rms_error.as_array());
    row("eq.17 σ", &s.predicted_sigma.as_array());
    println!();
    println!(
        "pass fraction            {:.4} ({} of {} runs)",
        s.pass_fraction,
        result.runs.iter().filter(|r| r.pass).count(),
        s.runs
    );
    println!("min separation           {:.1} m", s.min_separation_m);
    println!("adjustments per UAV-min  {:.1}", s.adjustments_per_uav_minute);
}

fn row(label: &str, v: &[f64; 6]) {
    print!("{label:<8}");
    if label.len() > 8 {
        println!();
        print!("{:<8}", "");
    }
    for e in v {
        print!("{e:>10.3}");
    }
    println!();
}
