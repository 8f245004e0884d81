//! The scene of the controller benchmarks: a UAV at the origin with `n` neighbours on a 100 m
//! ring around it, one per azimuth area, all cruising at 250 km/h; the UAV 0.7 m off its slot,
//! so that a step adjusts.

use std::sync::Arc;

use proxform_core::angle::kmh;
use proxform_core::state::State9;
use proxform_core::{Formation, FormationFrame, FormationSlot, Observation, ObservationSource, UavId};

/// The UAV's slot at the origin and `n` slots on the ring.
pub fn formation(n: usize) -> Arc<Formation> {
    let mut slots = vec![FormationSlot::at(0.0, 0.0, 0.0)];
    for k in 0..n {
        let a = (k as f64 + 0.5) * std::f64::consts::TAU / 8.0;
        slots.push(FormationSlot::at(100.0 * a.cos(), 100.0 * a.sin(), 0.0));
    }
    Arc::new(Formation { slots, frame: FormationFrame::World })
}

/// The neighbours' onboard observations (each in its slot) and the UAV's own state.
pub fn scene(formation: &Formation) -> (Vec<Observation>, State9) {
    let state_of = |s: &FormationSlot| {
        State9::from_column_slice(&[s.offset_m.x, s.offset_m.y, 0.0, kmh(250.0), 0.3, 0.0, 0.05, 0.02, 0.01])
    };
    let obs = formation.slots[1..]
        .iter()
        .enumerate()
        .map(|(k, s)| Observation {
            id: UavId(k as u32 + 1),
            state: state_of(s),
            age_s: 0.0,
            source: ObservationSource::Onboard,
        })
        .collect();
    let mut own = state_of(&formation.slots[0]);
    own[1] += 0.7; // off its slot: the step adjusts
    (obs, own)
}
