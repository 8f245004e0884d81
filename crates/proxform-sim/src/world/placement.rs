//! The starting states of one run: every UAV in its slot, or the followers scattered at random
//! in the scenario's box or disc (each start drawn from the UAV's own placement stream, again
//! until it is the safety distance from every UAV already placed, the navigator first), or at
//! the scenario's explicit positions, or on the ground in a take-off row at rest. Velocities
//! and attitudes are otherwise the in-slot ones: the navigator's. With `assign_slots` the drawn
//! starts go to the followers whose slots make the total (or the largest) distance from start
//! to slot least ([`proxform_core::assignment`]).

use proxform_core::assignment::{self, AssignBy};
use proxform_core::state::{State9, X, Y, Z};
use proxform_scenario::placement::Placement;
use proxform_scenario::Scenario;

use crate::random::{RunKey, Source};
use crate::world::radio::uniform;

/// Draws per UAV before a start is kept whatever its distance (the loader admits only regions
/// with room to spare, where this is not reached).
const MAX_DRAWS: u32 = 10_000;

/// Every UAV's state at t = 0 in run `run`.
pub fn initial_states(sc: &Scenario, run: RunKey) -> Vec<State9> {
    let mut states = sc.initial().to_vec();
    let nav = sc.navigator().index();
    let n = states.len();
    let at = |s: &State9| [s[X], s[Y], s[Z]];
    let nav_at = at(&states[nav]);
    match sc.placement() {
        Placement::Slots => {}
        Placement::Row { spacing_m, below_m, assign } => {
            // A row along y under the centre of the followers' slots, on the ground, at rest.
            let followers: Vec<usize> = (0..n).filter(|&i| i != nav).collect();
            let centre = slots_centre(&states, &followers);
            let m = followers.len();
            let starts: Vec<[f64; 3]> = (0..m)
                .map(|k| [centre[0], centre[1] + (k as f64 - (m as f64 - 1.0) / 2.0) * spacing_m, nav_at[2] - below_m])
                .collect();
            let order = match assign {
                Some(by) => assigned(&starts, &followers, &states, *by),
                None => (0..m).collect(),
            };
            for (f, &i) in followers.iter().enumerate() {
                let s = &mut states[i];
                *s = State9::zeros();
                for k in 0..3 {
                    s[X + k] = starts[order[f]][k];
                }
            }
        }
        Placement::Explicit(list) => {
            for (id, p) in list {
                let s = &mut states[id.index()];
                for k in 0..3 {
                    s[X + k] = nav_at[k] + p[k];
                }
            }
        }
        region => {
            let followers = (0..n).filter(|&i| i != nav);
            let centre = slots_centre(&states, &followers.clone().collect::<Vec<_>>());
            let d2 = sc.safety_distance_m().powi(2);
            let key = run.at(0);
            let mut placed: Vec<[f64; 3]> = vec![nav_at];
            for i in followers.clone() {
                let mut rng = key.rng(i as u64, Source::Placement);
                let mut p = centre;
                for _ in 0..MAX_DRAWS {
                    let u = [uniform(&mut rng), uniform(&mut rng), uniform(&mut rng)];
                    p = match *region {
                        Placement::Box { size_m, .. } => std::array::from_fn(|k| centre[k] + (u[k] - 0.5) * size_m[k]),
                        Placement::Disc { radius_m, height_m, .. } => {
                            let (r, a) = (radius_m * u[0].sqrt(), std::f64::consts::TAU * u[1]);
                            [centre[0] + r * a.cos(), centre[1] + r * a.sin(), centre[2] + (u[2] - 0.5) * height_m]
                        }
                        _ => centre,
                    };
                    let apart = placed.iter().all(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>() >= d2);
                    if apart {
                        break;
                    }
                }
                placed.push(p);
            }
            let followers: Vec<usize> = (0..n).filter(|&i| i != nav).collect();
            let starts = &placed[1..];
            let order = match region {
                Placement::Box { assign: Some(by), .. } | Placement::Disc { assign: Some(by), .. } => {
                    assigned(starts, &followers, &states, *by)
                }
                _ => (0..followers.len()).collect(),
            };
            for (f, &i) in followers.iter().enumerate() {
                let p = starts[order[f]];
                for k in 0..3 {
                    states[i][X + k] = p[k];
                }
            }
        }
    }
    states
}

/// The centre of the followers' slots (their in-slot positions in `slots`).
fn slots_centre(slots: &[State9], followers: &[usize]) -> [f64; 3] {
    let m = followers.len().max(1) as f64;
    let mut centre = [0.0; 3];
    for &i in followers {
        for k in 0..3 {
            centre[k] += slots[i][X + k] / m;
        }
    }
    centre
}

/// For each follower (in `followers` order), the index of the start it takes: the assignment of
/// starts to the followers' slots (their positions in `slots`) by `by`.
fn assigned(starts: &[[f64; 3]], followers: &[usize], slots: &[State9], by: AssignBy) -> Vec<usize> {
    assignment::assign(
        followers.len(),
        starts.len(),
        |f, s| {
            let slot = &slots[followers[f]];
            (0..3).map(|k| (slot[X + k] - starts[s][k]).powi(2)).sum::<f64>().sqrt()
        },
        by,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_scenario::builtin::paper_spec;

    fn scattered(edit: impl FnOnce(&mut proxform_scenario::ScenarioSpec)) -> Scenario {
        Scenario::try_from(paper_spec().with(edit)).expect("valid")
    }

    #[test]
    fn a_take_off_row_stands_still_on_the_ground_under_the_slots() {
        let sc = scattered(|s| {
            s.vehicle.vx_min_kmh = Some(0.0);
            s.initial.placement = Some("row".into());
            s.initial.row_spacing_m = Some(60.0);
            s.initial.ground_below_m = Some(80.0);
        });
        let a = initial_states(&sc, RunKey::new(1, 0));
        assert_eq!(a, initial_states(&sc, RunKey::new(1, 7)), "a row is the same in every run");
        let nav = sc.navigator().index();
        let mut ys: Vec<f64> = Vec::new();
        for (i, s) in a.iter().enumerate().filter(|(i, _)| *i != nav) {
            assert!((s[Z] - (a[nav][Z] - 80.0)).abs() < 1e-9, "UAV{} not on the ground", i + 1);
            assert!((3..9).all(|k| s[k] == 0.0), "UAV{} not at rest and level", i + 1);
            ys.push(s[Y]);
        }
        ys.sort_by(f64::total_cmp);
        assert!(ys.windows(2).all(|w| (w[1] - w[0] - 60.0).abs() < 1e-9), "{ys:?}");
    }

    #[test]
    fn random_starts_are_seeded_apart_and_inside_their_region() {
        let sc = scattered(|s| {
            s.initial.placement = Some("disc".into());
            s.initial.radius_m = Some(1000.0);
            s.initial.height_m = Some(100.0);
        });
        let a = initial_states(&sc, RunKey::new(1, 0));
        assert_eq!(a, initial_states(&sc, RunKey::new(1, 0)), "same seed, same starts");
        assert_ne!(a, initial_states(&sc, RunKey::new(1, 1)), "another run, other starts");
        let slots = sc.initial();
        assert_eq!(a[0], slots[0], "the navigator starts on its path");
        let centre: Vec<f64> = (0..3).map(|k| (1..6).map(|i| slots[i][X + k]).sum::<f64>() / 5.0).collect();
        for r in 0..50 {
            let s = initial_states(&sc, RunKey::new(7, r));
            for i in 0..6 {
                assert_eq!(&s[i].as_slice()[3..], &slots[i].as_slice()[3..], "velocity and attitude as in the slot");
                if i > 0 {
                    assert!((s[i][X] - centre[0]).hypot(s[i][Y] - centre[1]) <= 1000.0 + 1e-9);
                    assert!((s[i][Z] - centre[2]).abs() <= 50.0 + 1e-9);
                }
                for j in 0..i {
                    let d = (0..3).map(|k| (s[i][X + k] - s[j][X + k]).powi(2)).sum::<f64>().sqrt();
                    assert!(d >= sc.safety_distance_m(), "run {r}: UAVs {i} and {j} start {d} m apart");
                }
            }
        }
    }

    #[test]
    fn assigned_slots_take_the_same_starts_with_the_least_total_distance() {
        let disc = |assign: bool| {
            scattered(|s| {
                s.initial.placement = Some("disc".into());
                s.initial.radius_m = Some(1000.0);
                s.initial.assign_slots = Some(assign);
            })
        };
        let (free, fixed) = (disc(true), disc(false));
        let total = |s: &[State9]| -> f64 {
            (1..6).map(|i| (0..3).map(|k| (s[i][X + k] - fixed.initial()[i][X + k]).powi(2)).sum::<f64>().sqrt()).sum()
        };
        let mut better = 0;
        for r in 0..40 {
            let (a, b) = (initial_states(&free, RunKey::new(3, r)), initial_states(&fixed, RunKey::new(3, r)));
            // The same starts, each taken once.
            let mut pa: Vec<[f64; 3]> = a[1..].iter().map(|s| [s[X], s[Y], s[Z]]).collect();
            let mut pb: Vec<[f64; 3]> = b[1..].iter().map(|s| [s[X], s[Y], s[Z]]).collect();
            pa.sort_by(|x, y| x.partial_cmp(y).expect("finite"));
            pb.sort_by(|x, y| x.partial_cmp(y).expect("finite"));
            assert_eq!(pa, pb, "run {r}");
            assert!(total(&a) <= total(&b) + 1e-3 * 5.0, "run {r}: {} > {}", total(&a), total(&b));
            better += usize::from(total(&a) < total(&b) - 1.0);
        }
        assert!(better > 30, "the assignment shortens the approach in most runs ({better} of 40)");
    }

    #[test]
    fn assigned_by_the_largest_distance_the_farthest_start_is_nearer() {
        let disc = |by: &str| {
            scattered(|s| {
                s.initial.placement = Some("disc".into());
                s.initial.radius_m = Some(1000.0);
                s.initial.assign_slots = Some(true);
                s.initial.assign_by = Some(by.into());
            })
        };
        let (total, largest) = (disc("total"), disc("largest"));
        let slots = total.initial();
        let far = |s: &[State9]| -> f64 {
            (1..6)
                .map(|i| (0..3).map(|k| (s[i][X + k] - slots[i][X + k]).powi(2)).sum::<f64>().sqrt())
                .fold(0.0, f64::max)
        };
        let mut nearer = 0;
        for r in 0..40 {
            let (a, b) = (initial_states(&largest, RunKey::new(5, r)), initial_states(&total, RunKey::new(5, r)));
            assert!(far(&a) <= far(&b) + 1e-2, "run {r}: {} > {}", far(&a), far(&b));
            nearer += usize::from(far(&a) < far(&b) - 1.0);
        }
        assert!(nearer >= 4, "the largest distance is shorter in some runs ({nearer} of 40)");
    }

    #[test]
    fn explicit_starts_are_where_the_file_puts_them_and_slots_stay_the_default() {
        let sc = scattered(|s| {
            s.initial.placement = Some("explicit".into());
            s.initial.uavs =
                vec![proxform_scenario::spec::InitialUavSpec { id: Some(3), position_m: Some([-500.0, 300.0, 40.0]) }];
        });
        let s = initial_states(&sc, RunKey::new(1, 0));
        let nav = sc.initial()[0];
        assert_eq!([s[2][X] - nav[X], s[2][Y] - nav[Y], s[2][Z] - nav[Z]], [-500.0, 300.0, 40.0]);
        assert_eq!(s[1], sc.initial()[1], "the others in their slots");
        let paper = Scenario::try_from(paper_spec()).expect("valid");
        assert_eq!(initial_states(&paper, RunKey::new(1, 0)), paper.initial());
    }
}
