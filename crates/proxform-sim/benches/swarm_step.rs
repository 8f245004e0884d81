//! One engine step of the swarm scenario (perception, control and plant of every UAV), on the
//! reference engine and on the fast engine.

use proxform_scenario::builtin::swarm;
use proxform_sim::fast::FastSimulation;
use proxform_sim::{RunOptions, Simulation};

fn main() {
    divan::main();
}

#[divan::bench(args = [1_000, 10_000], sample_count = 20)]
fn swarm_step(bencher: divan::Bencher, uavs: usize) {
    let scenario = swarm(uavs).expect("valid");
    let mut sim = Simulation::new(&scenario, RunOptions::default(), 1, 0);
    for _ in 0..5 {
        sim.step();
    }
    bencher.counter(divan::counter::ItemsCount::new(uavs - 1)).bench_local(|| sim.step());
}

#[divan::bench(args = [1_000, 10_000], sample_count = 20)]
fn swarm_step_fast(bencher: divan::Bencher, uavs: usize) {
    let scenario = swarm(uavs).expect("valid");
    let mut sim = FastSimulation::new(&scenario, RunOptions::default(), 1, 0).expect("the fast engine runs the swarm");
    for _ in 0..5 {
        sim.step();
    }
    bencher.counter(divan::counter::ItemsCount::new(uavs - 1)).bench_local(|| sim.step());
}
