//! One whole run of the paper experiment (6 UAVs, 1000 steps), without recording.

use proxform_scenario::builtin::paper;
use proxform_sim::{run_one, RunOptions};

fn main() {
    divan::main();
}

#[divan::bench(sample_count = 30)]
fn paper_run(bencher: divan::Bencher) {
    let scenario = paper();
    let mut run = 0;
    bencher.bench_local(|| {
        run += 1;
        divan::black_box(run_one(&scenario, RunOptions::default(), 1, run, false))
    });
}
