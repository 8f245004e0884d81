//! The mission plan, as every UAV knows it before the flight, and how a neighbour's report is
//! brought forward in time with it (METHOD §3, "Reports brought forward").
//!
//! A report of a neighbour measured at t₀ (a radio message that took its time to arrive, a
//! track coasting over lost reports) says where the neighbour was and how it moved then. Its
//! track extrapolates it one update period with the rates it has filtered: what the
//! neighbour's own corrections do over a period. Beyond that, its own corrections do not last
//! (a follower adjusts every period), and extrapolating their noisy rates over a long delay
//! feeds a neighbour's noise back into the formation amplified (two followers leaning on each
//! other over a 0.3 s radio then oscillate). What lasts is the formation's motion, which the
//! plan gives: over the rest of the interval the report moves as the plan does (its
//! displacement, its change of velocity and of attitude), and in a formation frame that turns
//! with the course or the heading, the report's velocity relative to the plan turns with it.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::angle;
use crate::formation::FormationFrame;
use crate::state::{self, State9};

/// The navigator's planned state at a time (s), from any fixed start: only its differences
/// over time are used.
pub trait Plan: std::fmt::Debug + Send + Sync {
    /// The planned state at `t_s`: a function of `t_s` alone (a [`Carry`] remembers the
    /// states it asked for last).
    fn state_at(&self, t_s: f64) -> State9;
}

/// Slots of the per-thread memo of planned states ([`Carry::plan_state`]).
const MEMO: usize = 16;

/// Identities of the carries, for the memo (a carry and its clones share one).
static NEXT_CARRY: AtomicU64 = AtomicU64::new(1);

thread_local! {
    /// The planned states a thread asked for last, by (carry, time): within a step every UAV
    /// brings its tracks to the same few times, and a plan's state costs hundreds of
    /// instructions (a path's profile, its sines and cosines). The state is a function of the
    /// time, so the memo changes no result.
    static PLAN_STATES: RefCell<[(u64, u64, State9); MEMO]> = RefCell::new([(0, 0, State9::zeros()); MEMO]);
}

/// How reports are brought forward: the plan, the frame the formation turns in, and the
/// update period over which a track's own rates carry a report first.
#[derive(Debug, Clone)]
pub struct Carry {
    plan: Arc<dyn Plan>,
    frame: FormationFrame,
    period_s: f64,
    /// This carry's key in the memo of planned states.
    id: u64,
}

impl Carry {
    /// Reports carried by `plan` in a formation of frame `frame`, beyond `period_s`.
    pub fn new(plan: Arc<dyn Plan>, frame: FormationFrame, period_s: f64) -> Self {
        Self { plan, frame, period_s, id: NEXT_CARRY.fetch_add(1, Ordering::Relaxed) }
    }

    /// The plan's state at `t`, from this thread's memo when asked for lately.
    #[inline]
    fn plan_state(&self, t: f64) -> State9 {
        let bits = t.to_bits();
        let slot = ((bits ^ (bits >> 31) ^ self.id.wrapping_mul(0x9e37_79b9_7f4a_7c15)) % MEMO as u64) as usize;
        PLAN_STATES.with_borrow_mut(|memo| {
            let (id, at, state) = &mut memo[slot];
            if *id != self.id || *at != bits {
                *state = self.plan.state_at(t);
                (*id, *at) = (self.id, bits);
            }
            *state
        })
    }

    /// The plan.
    pub fn plan(&self) -> &Arc<dyn Plan> {
        &self.plan
    }

    /// The update period (s): a track's own rates carry a report that long.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// A neighbour's state `s` at `ta` brought to `t1` as the formation moves by the plan: it
    /// keeps its place relative to the planned navigator in the formation frame (which turns
    /// with the plan's course or heading, by Δψ from `ta` to `t1`; not in the world frame), and
    /// the deviation of its velocity from that place's, turned by Δψ; its attitude changes as
    /// the plan's. `s` itself for `t1 ≤ ta`.
    pub fn carry(&self, s: &State9, ta: f64, t1: f64) -> State9 {
        let h = t1 - ta;
        if h.is_nan() || h <= 0.0 {
            return *s;
        }
        let (pa, p1) = (self.plan_state(ta), self.plan_state(t1));
        let (ca, sa) = self.frame.course_cos_sin(&pa);
        let (c1, s1) = self.frame.course_cos_sin(&p1);
        // The frame's turn from ta to t1, Δψ, and its mean rate ω̄.
        let (c, sn) = (c1 * ca + s1 * sa, s1 * ca - c1 * sa);
        let omega = sn.atan2(c) / h;
        let turn = |v: [f64; 3]| [c * v[0] - sn * v[1], sn * v[0] + c * v[1], v[2]];
        // Its place relative to the planned navigator, then and turned.
        let r = [s[state::X] - pa[state::X], s[state::Y] - pa[state::Y], s[state::Z] - pa[state::Z]];
        let r1 = turn(r);
        // Its velocity's deviation from its place's (the plan's plus ω̄ × r), turned.
        let dev = turn([
            s[state::VX] - pa[state::VX] + omega * r[1],
            s[state::VY] - pa[state::VY] - omega * r[0],
            s[state::VZ] - pa[state::VZ],
        ]);
        let place_v = [p1[state::VX] - omega * r1[1], p1[state::VY] + omega * r1[0], p1[state::VZ]];
        let mut out = *s;
        for k in 0..3 {
            out[state::X + k] = p1[state::X + k] + r1[k];
            out[state::VX + k] = place_v[k] + dev[k];
            let a = state::ALPHA + k;
            out[a] = angle::wrap_pi(s[a] + angle::wrap_pi(p1[a] - pa[a]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Straight at 10 m/s along x, accelerating at 2 m/s² from t = 5 s, yawing slowly.
    #[derive(Debug)]
    struct Speeding;

    impl Plan for Speeding {
        fn state_at(&self, t: f64) -> State9 {
            let mut s = State9::zeros();
            let late = (t - 5.0).max(0.0);
            s[state::X] = 10.0 * t + late * late;
            s[state::VX] = 10.0 + 2.0 * late;
            s[state::BETA] = 0.01 * t;
            s
        }
    }

    #[test]
    fn a_report_moves_as_the_plan_does() {
        let carry = Carry::new(Arc::new(Speeding), FormationFrame::World, 0.1);
        // A neighbour 50 m to the side, 0.3 m/s slower than the plan, at 4.8 s: carried to
        // 5.4 s across the start of the acceleration.
        let mut s = Speeding.state_at(4.8);
        s[state::Y] = 50.0;
        s[state::VX] -= 0.3;
        let c = carry.carry(&s, 4.8, 5.4);
        let p = Speeding.state_at(5.4);
        assert!((c[state::VX] - (p[state::VX] - 0.3)).abs() < 1e-12, "{c:?}");
        // In the world frame its 0.3 m/s off the plan is a correction, which does not last: its
        // position moves as the plan's.
        assert!((c[state::X] - p[state::X]).abs() < 1e-12, "{c:?}");
        assert!((c[state::Y] - 50.0).abs() < 1e-12 && (c[state::BETA] - p[state::BETA]).abs() < 1e-12, "{c:?}");
        assert_eq!(carry.carry(&s, 4.8, 4.8), s, "no time, no change");
    }

    #[derive(Debug)]
    struct Turning;

    impl Plan for Turning {
        fn state_at(&self, t: f64) -> State9 {
            let (w, v) = (0.1, 40.0);
            let mut s = State9::zeros();
            let (sn, c) = (w * t).sin_cos();
            s[state::X] = v / w * sn;
            s[state::Y] = v / w * (1.0 - c);
            s[state::VX] = v * c;
            s[state::VY] = v * sn;
            s[state::BETA] = w * t;
            s
        }
    }

    #[test]
    fn in_a_frame_that_turns_a_report_keeps_its_place_and_its_deviation_turns() {
        // A slot 100 m to the left of a navigator turning left at 0.1 rad/s flies 10 m/s
        // slower: carried a second on, it is still there, turned by 0.1 rad.
        let carry = Carry::new(Arc::new(Turning), FormationFrame::Course, 0.1);
        let mut s = Turning.state_at(0.0);
        s[state::Y] += 100.0;
        s[state::VX] -= 10.0;
        let c = carry.carry(&s, 0.0, 1.0);
        let p = Turning.state_at(1.0);
        let (sn, co) = 0.1f64.sin_cos();
        assert!((c[state::X] - (p[state::X] - 100.0 * sn)).abs() < 1e-9, "{c:?}");
        assert!((c[state::Y] - (p[state::Y] + 100.0 * co)).abs() < 1e-9, "{c:?}");
        assert!((c[state::VX] - (p[state::VX] - 10.0 * co)).abs() < 1e-9, "{c:?}");
        assert!((c[state::VY] - (p[state::VY] - 10.0 * sn)).abs() < 1e-9, "{c:?}");
        // 1 m/s off its place's velocity: still 1 m/s off, turned with the frame.
        s[state::VY] += 1.0;
        let d = carry.carry(&s, 0.0, 1.0);
        assert!(
            (d[state::VX] - (c[state::VX] - sn)).abs() < 1e-9 && (d[state::VY] - (c[state::VY] + co)).abs() < 1e-9,
            "{d:?}"
        );
        // The world frame does not turn: the place moves as the plan does.
        let world = Carry::new(Arc::new(Turning), FormationFrame::World, 0.1).carry(&s, 0.0, 1.0);
        assert!((world[state::VX] - (p[state::VX] - 10.0)).abs() < 1e-9, "{world:?}");
        assert!((world[state::Y] - (p[state::Y] + 100.0)).abs() < 1e-9, "{world:?}");
    }
}
