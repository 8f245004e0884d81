//! Collision avoidance (beyond the paper, METHOD §8): how fast a UAV may close on each
//! neighbour it perceives.
//!
//! The paper's envelope centre pulls a UAV toward its slot with nothing to keep it off the UAVs
//! between it and that slot: harmless in formation, where every UAV is near its slot, but from
//! scattered starts or through a change of formation the paths cross. Separation keeping
//! (`separation_m`) pushes the centre away from close neighbours by a few tens of metres, which
//! a centre a kilometre away outweighs. This rule is a limit instead: the speed at which the
//! UAV closes on neighbour j, `c = −(v_des − v_j)·n̂` with `n̂` from j to the UAV, may not
//! exceed `√(2·a·(d − d_min − c·Δt))`, what the UAV's own braking `a` stops before `d_min`
//! (and, once within `d_min`, it must open at `(d_min − d)` per second). Where the centre's
//! velocity `v_des` closes faster, the excess along `n̂` is taken out, within the velocities the vehicle can fly
//! (every neighbour four times over, alternating with the vehicle's limits); while a limit binds, the UAV flies that velocity instead of the
//! centre's position (the position part of the target becomes the velocity's own step), so the
//! remaining pull toward the slot slides it around the neighbour, at least as fast as the
//! closing speed taken out, and to its right when nothing else decides the side (two UAVs
//! head-on, each blocking the other's way to its slot, would otherwise stop nose to nose). Each UAV brakes as if the
//! other did not: two that both apply it keep twice the margin, and the navigator, which does
//! not apply it, is avoided all the same.

use crate::formation::{Formation, FormationSlot};
use crate::observation::{Observation, ObservationSource, UavId};
use crate::state::{State9, VX, X};
use crate::vehicle::VehicleModel;

use super::{ControllerParams, SEPARATION_SLOT_FRACTION};

/// One perceived neighbour, predicted to the next update: position, velocity, and how close
/// it may come (m).
#[derive(Debug, Clone, Copy)]
pub(super) struct Near {
    id: UavId,
    pos: [f64; 3],
    vel: [f64; 3],
    /// The slots' share of the distance (`None`: the avoidance distance alone).
    slot_limit: Option<f64>,
    /// Distance from the UAV's own next position (m), to order the limits.
    d: f64,
}

impl Near {
    /// Neighbour `id` observed at `x_j`, `h` s before the next update (the period, plus the
    /// observation's age: a radio report or a relay describes where the neighbour was), for
    /// the UAV in `slot_i` that will then be at `x_hold`.
    #[inline]
    fn new(formation: &Formation, id: UavId, x_j: &State9, h: f64, slot_i: &FormationSlot, x_hold: &State9) -> Self {
        let pos = [x_j[X] + h * x_j[VX], x_j[X + 1] + h * x_j[VX + 1], x_j[X + 2] + h * x_j[VX + 2]];
        let p = [x_hold[X] - pos[0], x_hold[X + 1] - pos[1], x_hold[X + 2] - pos[2]];
        Self {
            id,
            pos,
            vel: [x_j[VX], x_j[VX + 1], x_j[VX + 2]],
            slot_limit: formation.slot(id).map(|s| SEPARATION_SLOT_FRACTION * (s.offset_m - slot_i.offset_m).norm()),
            d: (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt(),
        }
    }
}

/// Which UAVs a sensor serving the collision avoidance reports besides the nearest of each
/// azimuth area: every UAV within [`super::AVOID_WATCH`] avoidance distances (one hidden behind
/// another in its area may be the one closing fastest), and every UAV in sensing range closing
/// fast enough that the rule may bind on it, whatever its distance: a pair closing at 40 m/s
/// needs some 140 m to stop short of the avoidance distance, more than a fixed radius gives.
/// "Fast enough" counts on twice the present closing speed (the UAVs' velocities change
/// while they close), so that the rule sees it before it binds.
///
/// Beyond the distance at which no pair closing at the largest relative speed of the step
/// could bind ([`Self::for_speeds`]), the closing test is not made: nothing there is reported
/// either way, and a swarm flying steadily reads no neighbour's velocity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CloseWatch {
    /// Squared radius within which every UAV is reported (m²; 0: none).
    near2: f64,
    /// Squared radius beyond which none is (m²; 0: none known, the test decides).
    far2: f64,
    /// The avoidance distance (m) and the braking the rule counts on (m/s²); 0: no closing
    /// test.
    avoid_m: f64,
    braking_mps2: f64,
    /// The update period (s).
    dt_s: f64,
}

impl CloseWatch {
    /// The watch of a rule with avoidance distance `avoid_m`, braking `braking_mps2` and
    /// update period `dt_s`, for a sensor of range `range_m` (no watch when `avoid_m` ≤ 0).
    pub fn new(avoid_m: f64, braking_mps2: f64, dt_s: f64, range_m: f64) -> Self {
        if !(avoid_m > 0.0 && braking_mps2 > 0.0) {
            return Self::default();
        }
        let near = (super::AVOID_WATCH * avoid_m).min(range_m);
        Self { near2: near * near, far2: 0.0, avoid_m, braking_mps2, dt_s }
    }

    /// The watch for a step in which no two UAVs move relative to each other faster than
    /// `max_relative_mps`: beyond `avoid_m + c·Δt + c²/(2a)`, c twice that speed, the closing
    /// test could not report anything.
    pub fn for_speeds(mut self, max_relative_mps: f64) -> Self {
        if self.avoid_m > 0.0 && max_relative_mps.is_finite() {
            let c = 2.0 * max_relative_mps.max(0.0);
            let far = self.avoid_m + c * self.dt_s + c * c / (2.0 * self.braking_mps2);
            self.far2 = far * far;
        }
        self
    }

    /// Whether a UAV `d2` m² away may be reported without knowing its velocity: false when
    /// [`Self::sees`] is false whatever its velocity this step.
    #[inline]
    pub fn may_see(&self, d2: f64) -> bool {
        d2 < self.near2 || (self.avoid_m > 0.0 && (self.far2 == 0.0 || d2 < self.far2))
    }

    /// Whether a UAV at `p` from the observer (m, `d2` = |p|²) moving at `w` relative to it
    /// (m/s) is reported.
    #[inline]
    pub fn sees(&self, d2: f64, p: [f64; 3], w: [f64; 3]) -> bool {
        if d2 < self.near2 {
            return true;
        }
        if self.far2 > 0.0 && d2 >= self.far2 {
            return false;
        }
        let pw = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
        if self.avoid_m <= 0.0 || pw >= 0.0 {
            return false;
        }
        let d = d2.sqrt();
        let c = -2.0 * pw / d;
        d - self.avoid_m - c * self.dt_s < c * c / (2.0 * self.braking_mps2)
    }
}

/// A bound on the speed of any of `velocities` relative to any other: twice the largest
/// distance of one from the first (0 for none).
pub fn relative_speed_bound(velocities: impl Iterator<Item = [f64; 3]>) -> f64 {
    let mut first: Option<[f64; 3]> = None;
    let mut far2 = 0.0f64;
    for v in velocities {
        let f = *first.get_or_insert(v);
        far2 = far2.max((v[0] - f[0]).powi(2) + (v[1] - f[1]).powi(2) + (v[2] - f[2]).powi(2));
    }
    2.0 * far2.sqrt()
}

/// The side on which the UAV passes a neighbour, and for how long its limit has bound.
#[derive(Debug, Clone, Copy)]
struct Side {
    id: UavId,
    /// Unit vector, perpendicular to the line to the neighbour when chosen.
    t_hat: [f64; 3],
    /// Seconds the limit has bound, with breaks shorter than [`SIDE_MEMORY_S`].
    bound_s: f64,
    /// Seconds since the limit last bound.
    idle_s: f64,
    /// Whether the side is already the right one (after [`LOCK_S`]).
    right: bool,
}

/// After this long (s) passing a neighbour on the side its centre asked for, a UAV passes on
/// the right instead: two UAVs that chose the same side (each asked to go the same way) slide
/// together and never pass; on their rights they slide apart.
const LOCK_S: f64 = 10.0;

/// A side is forgotten once its neighbour's limit has not bound for this long (s).
const SIDE_MEMORY_S: f64 = 2.0;

/// The rule's parameters and its list of neighbours, allocated once. Public so that an engine
/// that steps many UAVs as arrays can run the same rule for the few UAVs it binds on (see
/// [`Avoidance::remembers`]).
#[derive(Debug, Clone)]
pub struct Avoidance {
    /// `avoid_m`: no neighbour closer (m).
    distance_m: f64,
    /// `a`: the deceleration counted on (m/s²).
    braking_mps2: f64,
    /// This step's perceived neighbours.
    near: Vec<Near>,
    /// The side on which the UAV passes each neighbour whose limit bound in the last update
    /// (a unit vector): kept while the limit binds, so that the UAV does not turn this way and
    /// that as the geometry wavers.
    sides: Vec<Side>,
    /// The neighbours whose limit bound in this update (working memory).
    bound_now: Vec<UavId>,
}

/// What collision avoidance remembers of one UAV from one update to the next: the sides it
/// passes its neighbours on ([`Avoidance::exchange_memory`]), 48 bytes a side.
#[derive(Debug, Clone, Default)]
pub struct AvoidanceMemory {
    sides: Vec<Side>,
}

impl AvoidanceMemory {
    /// Whether it remembers a side.
    pub fn remembers(&self) -> bool {
        !self.sides.is_empty()
    }

    /// Bytes held (the struct and its list).
    pub fn heap_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.sides.capacity() * std::mem::size_of::<Side>()
    }
}

/// When a neighbour's limit first binds, a UAV already sliding past it at this share of the
/// closing speed taken out (and faster than [`SLIDE_NOISE_MPS`]) passes it on that side;
/// slower than that, on the right.
const SLIDE_COMMITTED: f64 = 0.25;
/// A side on which the UAV slides slower than this share of the closing speed taken out is
/// closed by the vehicle's limits: the other side may take over.
const SIDE_OPEN: f64 = 0.5;
/// Slides slower than this (m/s) do not decide the side.
const SLIDE_NOISE_MPS: f64 = 1.0;

/// Most passes over the neighbours (a later limit, or the vehicle's, can undo part of an
/// earlier one); the nearest neighbour's limit comes last in each, so it is the one that holds
/// when not all can.
const PASSES: usize = 8;

impl Avoidance {
    /// The rule for avoidance distance `distance_m` (m) and deceleration `braking_mps2` (m/s²).
    pub fn new(distance_m: f64, braking_mps2: f64) -> Self {
        Self {
            distance_m,
            braking_mps2,
            // Grown when first needed: most UAVs of a large swarm never come close enough.
            near: Vec::new(),
            sides: Vec::new(),
            bound_now: Vec::new(),
        }
    }

    /// Exchanges what the rule remembers from one update to the next (the sides it passes its
    /// neighbours on) with `memory`; its working lists are rebuilt every update. An engine that
    /// keeps the memory of many UAVs keeps an [`AvoidanceMemory`] per UAV that remembers, and
    /// lends it to one working rule for the UAV's update.
    pub fn exchange_memory(&mut self, memory: &mut AvoidanceMemory) {
        std::mem::swap(&mut self.sides, &mut memory.sides);
    }

    /// Bytes held (the struct and its lists).
    pub fn heap_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.near.capacity() * std::mem::size_of::<Near>()
            + self.sides.capacity() * std::mem::size_of::<Side>()
            + self.bound_now.capacity() * std::mem::size_of::<UavId>()
    }

    /// Takes this update's neighbours: every UAV perceived, not only the nearest of each
    /// azimuth area (one hidden behind another in its area may be the one closing fastest),
    /// extrapolated to the next update at its velocity (from the moment it describes: a radio
    /// report's or a relay's age included). A report older than `track_timeout_s` (a relay's
    /// information, carried hop by hop) says too little of where a UAV is now to avoid it.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    pub fn perceive(
        &mut self,
        formation: &Formation,
        me: UavId,
        slot_i: &FormationSlot,
        x_hold: &State9,
        params: &ControllerParams,
        observations: &[Observation],
    ) {
        self.near.clear();
        let r2 = params.areas.sensing_range_m.powi(2);
        // A UAV reported twice (onboard and by radio) stands twice: the same limit, met by the
        // same velocity, costs less than looking for it.
        for o in observations {
            if o.id == me || o.age_s > params.track_timeout_s {
                continue;
            }
            let n = Near::new(formation, o.id, &o.state, o.age_s + params.dt_s, slot_i, x_hold);
            if o.source == ObservationSource::Onboard && n.d * n.d > r2 {
                continue;
            }
            self.near.push(n);
        }
    }

    /// Limits the centre `o_i` (as `O_i − X_hold`, X_hold the UAV's state next update if it
    /// keeps its course) so that the UAV closes on no neighbour faster than it can stop.
    /// True when a limit bound.
    /// `goal` is where the centre is, from X_hold (m).
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    pub fn limit(
        &mut self,
        vehicle: &VehicleModel,
        x_hold: &State9,
        dt: f64,
        o_i: &mut State9,
        goal: &[f64; 3],
    ) -> bool {
        // The velocity the centre asks for, as far as the vehicle can fly it: limits on a
        // velocity it cannot reach would bind on nothing.
        let v_des =
            vehicle.clamp_velocity([x_hold[VX] + o_i[VX], x_hold[VX + 1] + o_i[VX + 1], x_hold[VX + 2] + o_i[VX + 2]]);
        if self.near.iter().all(|n| self.excess(n, x_hold, dt, &v_des).is_none()) {
            self.bound_now.clear();
            self.forget(dt);
            return false;
        }
        // Farthest first, so the nearest neighbour's limit is applied last.
        self.near.sort_unstable_by(|a, b| b.d.total_cmp(&a.d));
        self.bound_now.clear();
        let mut v = v_des;
        for _ in 0..PASSES {
            let mut changed = false;
            for n in &self.near {
                let Some((excess, n_hat)) = self.excess(n, x_hold, dt, &v) else { continue };
                // Pass it: on the side chosen when its limit first bound; a new one on the side
                // the centre asks for when it clearly asks, otherwise to the right (two UAVs
                // head-on both keep right and pass each other). At least at the closing
                // speed taken out.
                let rel = [v[0] - n.vel[0], v[1] - n.vel[1], v[2] - n.vel[2]];
                let slide = perpendicular(rel, n_hat);
                let speed = norm(slide);
                let kept = self.sides.iter().find(|s| s.id == n.id).map(|s| (perpendicular(s.t_hat, n_hat), s));
                let (mut t_hat, mut right) = match kept {
                    Some((_, s)) if s.bound_s >= LOCK_S && !s.right => (right_of(n_hat), true),
                    Some((t, s)) if norm(t) > 0.1 => (scale(t, 1.0 / norm(t)), s.right),
                    _ if speed > (SLIDE_COMMITTED * excess).max(SLIDE_NOISE_MPS) => (scale(slide, 1.0 / speed), false),
                    _ => (right_of(n_hat), true),
                };
                // Only when the centre lies beyond the neighbour (nearer than d_min to it, or
                // past it) does the UAV pass it: short of it, braking alone is enough.
                let toward_goal = -(goal[0] * n_hat[0] + goal[1] * n_hat[1] + goal[2] * n_hat[2]);
                let passing = toward_goal > n.d - self.d_min(n);
                let try_side = |t: [f64; 3]| {
                    let along_side = slide[0] * t[0] + slide[1] * t[1] + slide[2] * t[2];
                    let more = if passing { (excess - along_side).max(0.0) } else { 0.0 };
                    let w = vehicle.clamp_velocity([
                        v[0] + excess * n_hat[0] + more * t[0],
                        v[1] + excess * n_hat[1] + more * t[1],
                        v[2] + excess * n_hat[2] + more * t[2],
                    ]);
                    let achieved = (w[0] - n.vel[0]) * t[0] + (w[1] - n.vel[1]) * t[1] + (w[2] - n.vel[2]) * t[2];
                    (w, achieved)
                };
                let (mut w, achieved) = try_side(t_hat);
                if passing && achieved < SIDE_OPEN * excess {
                    // A side the vehicle's limits close (it already flies that way nearly as
                    // fast as it can) is no way past: the other side, if it gets past faster.
                    // Only a side so closed gives way: two open sides compared step by step
                    // would trade places as the geometry wavers, and the UAV would swing
                    // between them without passing.
                    let other = scale(t_hat, -1.0);
                    let (w_other, achieved_other) = try_side(other);
                    if achieved_other > achieved + SLIDE_NOISE_MPS {
                        (w, t_hat, right) = (w_other, other, false);
                    }
                }
                if !self.bound_now.contains(&n.id) {
                    self.bound_now.push(n.id);
                    match self.sides.iter_mut().find(|s| s.id == n.id) {
                        Some(s) => {
                            s.t_hat = t_hat;
                            s.right = right;
                            s.bound_s += dt;
                            s.idle_s = 0.0;
                        }
                        None => self.sides.push(Side { id: n.id, t_hat, bound_s: dt, idle_s: 0.0, right }),
                    }
                }
                v = w;
                changed = true;
            }
            if !changed {
                break;
            }
        }
        self.forget(dt);
        for k in 0..3 {
            o_i[VX + k] = v[k] - x_hold[VX + k];
            o_i[X + k] = 0.5 * dt * o_i[VX + k];
        }
        true
    }

    /// Whether [`Self::limit`] could bind on any of `observations` for the centre `o_i` (as
    /// `O_i − X_hold`): false only when, for every one, even closing at the full relative
    /// speed `w` leaves room to stop, `d − d_avoid − w·Δt ≥ w²/(2a)` (the limit with `d_min` at
    /// its largest). Observations older than `max_age_s` do not count, as in [`Self::perceive`]
    /// (`track_timeout_s`). A rule that remembers no side and could bind on nothing leaves the centre
    /// and itself as they are, so the caller may skip it (and the list it would fill).
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    pub fn may_bind(
        &self,
        vehicle: &VehicleModel,
        x_hold: &State9,
        dt: f64,
        o_i: &State9,
        observations: &[Observation],
        max_age_s: f64,
    ) -> bool {
        let v =
            vehicle.clamp_velocity([x_hold[VX] + o_i[VX], x_hold[VX + 1] + o_i[VX + 1], x_hold[VX + 2] + o_i[VX + 2]]);
        // Written out component by component: it runs over every observation of every UAV's
        // update, and the generic array and iterator forms did not always inline.
        let h = x_hold.as_slice();
        observations.iter().any(|o| {
            if o.age_s > max_age_s {
                return false;
            }
            let x = o.state.as_slice();
            let ahead = o.age_s + dt;
            let px = h[X] - (x[X] + ahead * x[VX]);
            let py = h[X + 1] - (x[X + 1] + ahead * x[VX + 1]);
            let pz = h[X + 2] - (x[X + 2] + ahead * x[VX + 2]);
            let d = (px * px + py * py + pz * pz).sqrt();
            let (wx, wy, wz) = (v[0] - x[VX], v[1] - x[VX + 1], v[2] - x[VX + 2]);
            let w2 = wx * wx + wy * wy + wz * wz;
            d - self.distance_m - w2.sqrt() * dt < w2 / (2.0 * self.braking_mps2)
        })
    }

    /// Whether the rule remembers a side for some neighbour: while it does, its next
    /// [`Self::limit`] depends on this one's. A rule that remembers nothing and binds on no
    /// neighbour leaves the centre as it is and stays as it was, so an engine may run a fresh
    /// one in its place.
    pub fn remembers(&self) -> bool {
        !self.sides.is_empty()
    }

    /// Ages the sides of the neighbours whose limit did not bind this update, and forgets
    /// those idle for longer than [`SIDE_MEMORY_S`].
    fn forget(&mut self, dt: f64) {
        let bound_now = &self.bound_now;
        for s in self.sides.iter_mut().filter(|s| !bound_now.contains(&s.id)) {
            s.idle_s += dt;
        }
        self.sides.retain(|s| s.idle_s <= SIDE_MEMORY_S);
    }

    /// How close neighbour `n` may come (m).
    #[inline]
    fn d_min(&self, n: &Near) -> f64 {
        n.slot_limit.map_or(self.distance_m, |s| s.min(self.distance_m))
    }

    /// How much faster than allowed velocity `v` closes on neighbour `n`, and the direction
    /// from it to the UAV; None when within the limit.
    #[inline]
    fn excess(&self, n: &Near, x_hold: &State9, dt: f64, v: &[f64; 3]) -> Option<(f64, [f64; 3])> {
        let d = n.d;
        if d < 1e-9 {
            return None;
        }
        let n_hat = [(x_hold[X] - n.pos[0]) / d, (x_hold[X + 1] - n.pos[1]) / d, (x_hold[X + 2] - n.pos[2]) / d];
        let closing = -((v[0] - n.vel[0]) * n_hat[0] + (v[1] - n.vel[1]) * n_hat[1] + (v[2] - n.vel[2]) * n_hat[2]);
        let d_min = self.d_min(n);
        let room = d - d_min - closing.max(0.0) * dt;
        // Within d_min already: open at (d_min − d) per second.
        let c_max = if room > 0.0 { (2.0 * self.braking_mps2 * room).sqrt() } else { room };
        // A small tolerance, so that a limit met to rounding does not count again.
        (closing > c_max + 1e-9).then_some((closing - c_max, n_hat))
    }
}

/// The unit vector to the right of a UAV heading toward `−n_hat` (`n_hat` from the neighbour
/// to the UAV), horizontal: `(−n̂) × ẑ`; for a neighbour straight above or below, `ŷ`.
#[inline]
fn right_of(n_hat: [f64; 3]) -> [f64; 3] {
    // (−n̂) × ẑ = (−n̂y, n̂x, 0)
    let (x, y) = (-n_hat[1], n_hat[0]);
    let h = (x * x + y * y).sqrt();
    if h < 1e-6 {
        return [0.0, 1.0, 0.0];
    }
    [x / h, y / h, 0.0]
}

/// `a` without its component along the unit vector `n`.
#[inline]
fn perpendicular(a: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let along = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    [a[0] - along * n[0], a[1] - along * n[1], a[2] - along * n[2]]
}

#[inline]
fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[inline]
fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::KinematicModel;

    fn near(id: u32, pos: [f64; 3], vel: [f64; 3], me: [f64; 3]) -> Near {
        let p = [me[0] - pos[0], me[1] - pos[1], me[2] - pos[2]];
        Near { id: UavId(id), pos, vel, slot_limit: None, d: norm(p) }
    }

    fn goal(o_i: &State9) -> [f64; 3] {
        [o_i[X], o_i[X + 1], o_i[X + 2]]
    }

    fn own(pos: [f64; 3], vel: [f64; 3]) -> State9 {
        State9::from_column_slice(&[pos[0], pos[1], pos[2], vel[0], vel[1], vel[2], 0.0, 0.0, 0.0])
    }

    /// A centre 300 m to the right, straight through a neighbour 80 m away at the same speed
    /// (80 m/s: as much room to slow down as to speed up, 30 and 20 m/s).
    fn blocked() -> (Avoidance, State9, State9) {
        blocked_at(80.0)
    }

    fn blocked_at(vx: f64) -> (Avoidance, State9, State9) {
        let mut av = Avoidance::new(62.5, 2.5);
        let x_hold = own([0.0, 0.0, 0.0], [vx, 0.0, 0.0]);
        av.near.push(near(1, [0.0, -80.0, 0.0], [vx, 0.0, 0.0], [0.0; 3]));
        let mut o_i = State9::zeros();
        o_i[X + 1] = -300.0;
        o_i[VX + 1] = -300.0;
        (av, x_hold, o_i)
    }

    #[test]
    fn a_rule_that_may_not_bind_leaves_the_centre_as_it_is() {
        // Random neighbours around a UAV with random centres: whenever `may_bind` says no, the
        // rule run in full changes nothing (so skipping it is exact); and it says yes for a
        // neighbour closing fast.
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let params = ControllerParams::default();
        let slots: Vec<FormationSlot> = (0..4).map(|k| FormationSlot::at(-40.0 * k as f64, 0.0, 0.0)).collect();
        let formation = Formation::new(slots, crate::formation::FormationFrame::World).expect("finite");
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut skipped, mut bound) = (0, 0);
        for _ in 0..4000 {
            let x_hold = own([0.0, 0.0, 0.0], [60.0 + 10.0 * next(), 4.0 * next(), 2.0 * next()]);
            let obs: Vec<Observation> = (1..4)
                .map(|j| {
                    let mut st = State9::zeros();
                    for a in 0..3 {
                        st[X + a] = 240.0 * next();
                        st[VX + a] = x_hold[VX + a] + 30.0 * next();
                    }
                    // The third a radio report up to 1.5 s old (beyond the 1 s limit at times).
                    let (age_s, source) = match j {
                        3 => (1.5 * (next() + 0.5), ObservationSource::Radio),
                        _ => (0.0, ObservationSource::Onboard),
                    };
                    Observation { id: UavId(j), state: st, age_s, source }
                })
                .collect();
            let mut o_i = State9::zeros();
            for a in 0..3 {
                o_i[X + a] = 400.0 * next();
                o_i[VX + a] = 20.0 * next();
            }
            let mut av = Avoidance::new(30.0, 2.5);
            let may = av.may_bind(&vehicle, &x_hold, 0.1, &o_i, &obs, 1.0);
            let before = o_i;
            let g = goal(&o_i);
            av.perceive(&formation, UavId(0), &formation.slots[0], &x_hold, &params, &obs);
            let limited = av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g);
            if !may {
                skipped += 1;
                assert!(!limited && o_i == before && !av.remembers(), "{obs:?} {before:?}");
            }
            bound += usize::from(limited);
        }
        assert!(skipped > 500 && bound > 100, "skipped {skipped}, bound {bound}");
    }

    #[test]
    fn a_report_is_avoided_where_its_uav_is_now_not_where_it_was() {
        // A neighbour flying alongside at 80 m/s, 50 m away (beyond the 37.5 m avoidance
        // distance), reported 0.6 s late: where the report puts it, it is 31 m away.
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let params = ControllerParams { track_timeout_s: 1.0, ..ControllerParams::default() };
        let slots = vec![FormationSlot::at(0.0, 0.0, 0.0), FormationSlot::at(40.0, 30.0, 0.0)];
        let formation = Formation::new(slots, crate::formation::FormationFrame::World).expect("finite");
        let x_hold = own([0.0, 0.0, 0.0], [80.0, 0.0, 0.0]);
        let report = |age_s: f64| {
            let then = own([40.0 - 80.0 * age_s, 30.0, 0.0], [80.0, 0.0, 0.0]);
            vec![Observation { id: UavId(1), state: then, age_s, source: ObservationSource::Radio }]
        };
        let binds = |obs: &[Observation], max_age_s: f64| {
            let mut av = Avoidance::new(37.5, 2.5);
            let mut o_i = State9::zeros();
            let may = av.may_bind(&vehicle, &x_hold, 0.1, &o_i, obs, max_age_s);
            let p = ControllerParams { track_timeout_s: max_age_s, ..params.clone() };
            av.perceive(&formation, UavId(0), &formation.slots[0], &x_hold, &p, obs);
            let g = goal(&o_i);
            let limited = av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g);
            assert!(may || !limited);
            limited
        };
        assert!(!binds(&report(0.6), 1.0), "brought forward over its age, it is 50 m away");
        // A UAV that is where the report says (a fresh detection there) is avoided.
        let mut there = report(0.6);
        there[0].age_s = 0.0;
        assert!(binds(&there, 1.0));
        // A report older than the limit is not avoided at all.
        assert!(!binds(&there.iter().map(|o| Observation { age_s: 1.2, ..*o }).collect::<Vec<_>>(), 1.0));
    }

    #[test]
    fn closing_is_limited_to_what_braking_stops_and_the_uav_slides_past() {
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let (mut av, x_hold, mut o_i) = blocked();
        assert!({
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        });
        let v = [x_hold[VX] + o_i[VX], x_hold[VX + 1] + o_i[VX + 1], x_hold[VX + 2] + o_i[VX + 2]];
        // Closing on it (−y) at most √(2·2.5·(80 − 62.5 − c·0.1)) ≈ 9 m/s.
        assert!(-v[1] <= 9.5 && -v[1] > 5.0, "{v:?}");
        // Head-on, nothing decides the side: to the right of −y, i.e. back (−x), at least as
        // fast as the closing speed taken out (the vehicle's 20 m/s of vy less the limit).
        assert!(v[0] < 80.0 - 5.0, "{v:?}");
        // The target is now a velocity: its position part is that velocity's own step.
        assert!((o_i[X + 1] - 0.05 * o_i[VX + 1]).abs() < 1e-12);
    }

    #[test]
    fn a_side_once_chosen_is_kept_while_the_limit_binds() {
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let (mut av, x_hold, mut o_i) = blocked();
        {
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        };
        let first = av.sides[0].t_hat;
        // Next update the centre asks, slightly, for the other side: the UAV stays with its own.
        let (_, x_hold, mut o_i) = blocked();
        o_i[VX] = 3.0;
        av.near.clear();
        av.near.push(near(1, [0.0, -80.0, 0.0], [80.0, 0.0, 0.0], [0.0; 3]));
        {
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        };
        assert_eq!(av.sides[0].t_hat, first);
        assert!(o_i[VX] < 0.0, "{:?}", o_i.as_slice());
    }

    #[test]
    fn a_memory_lent_to_another_rule_keeps_its_side() {
        // The side chosen by one rule, kept as an AvoidanceMemory, lent to a fresh rule (as an
        // engine keeping many UAVs' memories lends each to its thread's rule): the fresh rule
        // stays on that side where one without the memory would take the other.
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let (mut av, x_hold, mut o_i) = blocked();
        let g = goal(&o_i);
        av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g);
        let first = av.sides[0].t_hat;
        let mut memory = AvoidanceMemory::default();
        av.exchange_memory(&mut memory);
        assert!(memory.remembers() && !av.remembers());
        // A few sides, none of the rule's working lists.
        let few = std::mem::size_of::<AvoidanceMemory>() + 4 * std::mem::size_of::<Side>();
        assert!(memory.heap_bytes() <= few, "{} > {few}", memory.heap_bytes());
        let next = |lend: Option<&mut AvoidanceMemory>| {
            let (mut fresh, x_hold, mut o_i) = blocked();
            o_i[VX] = 3.0;
            if let Some(m) = lend {
                fresh.exchange_memory(m);
            }
            let g = goal(&o_i);
            fresh.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g);
            fresh.sides[0].t_hat
        };
        assert_eq!(next(Some(&mut memory)), first);
        assert_ne!(next(None), first);
    }

    #[test]
    fn a_side_the_vehicle_cannot_fly_gives_way_to_the_other() {
        // At 52 m/s, 2 m/s above the vehicle's least speed: slowing down (the right) gets it
        // nowhere, so it passes on the left, speeding up.
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let (mut av, x_hold, mut o_i) = blocked_at(52.0);
        assert!({
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        });
        assert!(o_i[VX] > 5.0, "{:?}", o_i.as_slice());
        assert!(!av.sides[0].right);
    }

    #[test]
    fn a_neighbour_short_of_the_centre_is_braked_for_not_passed() {
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let (mut av, x_hold, mut o_i) = blocked();
        // The centre is 10 m toward the neighbour, which stays 70 m away: brake, no slide.
        o_i[X + 1] = -10.0;
        o_i[VX + 1] = -18.0;
        av.near[0].vel[1] = 0.0;
        assert!({
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        });
        assert!(o_i[VX].abs() < 1e-9, "{:?}", o_i.as_slice());
    }

    #[test]
    fn nothing_changes_when_no_neighbour_closes_fast() {
        let vehicle = VehicleModel::Kinematic(KinematicModel::default());
        let mut av = Avoidance::new(62.5, 2.5);
        let x_hold = own([0.0; 3], [60.0, 0.0, 0.0]);
        av.near.push(near(1, [0.0, -100.0, 0.0], [60.0, 0.5, 0.0], [0.0; 3]));
        let mut o_i = State9::zeros();
        o_i[X + 1] = -0.3;
        o_i[VX + 1] = -0.3;
        let before = o_i;
        assert!(!{
            let g = goal(&o_i);
            av.limit(&vehicle, &x_hold, 0.1, &mut o_i, &g)
        });
        assert_eq!(o_i, before);
    }

    #[test]
    fn the_watch_bounded_by_the_step_speeds_reports_what_the_unbounded_one_does() {
        // Random pairs moving relative to each other no faster than the bound: the bound
        // skips no pair the closing test would report, and beyond its distance reports none.
        let free = CloseWatch::new(62.5, 2.5, 0.1, 250.0);
        let mut seed = 99u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut seen = 0;
        for _ in 0..20_000 {
            let bound = 40.0 * (next() + 0.5);
            let bounded = free.for_speeds(bound);
            let p = [500.0 * next(), 500.0 * next(), 100.0 * next()];
            let w = [next(), next(), next()];
            let k = bound * (next() + 0.5) / norm(w).max(1e-9);
            let w = scale(w, k);
            let d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            let (a, b) = (free.sees(d2, p, w), bounded.sees(d2, p, w));
            assert_eq!(a, b, "p {p:?} w {w:?} bound {bound}");
            assert!(bounded.may_see(d2) || !a);
            seen += usize::from(a);
        }
        assert!(seen > 1000, "{seen}");
    }
}
