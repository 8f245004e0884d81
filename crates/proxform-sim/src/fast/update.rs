//! One UAV's update in the fast engine: perceive (the nearest UAV per azimuth area, the main
//! references, radio messages, close-range detections), measure (noise drawn in bulk for what
//! was observed), and the proximity controller's step (METHOD §6) on its array of tracks.
//!
//! The controller is the reference's ([`proxform_core::ProximityController::step`]) written
//! over the fast engine's data: positions relative to the UAV's reference point, tracks in
//! f32 ([`super::tracks`]), the one-step input in closed form (the kinematic vehicle's cost
//! Hessian is diagonal, so the reference's solver also takes one sweep). Collision avoidance is
//! the reference's own rule ([`proxform_core::controller::Avoidance`]), kept per UAV only while
//! it remembers a side.

use proxform_core::controller::{centre_from, push_apart, Avoidance};
use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{State9, ALPHA, BETA, VX, X};
use proxform_core::{Observation, ObservationSource, Outcome, UavId};
use proxform_scenario::Scenario;

use super::setup::Consts;
use super::tracks::Owner;
use crate::measure::observer::{StepOutcome, UavStep};
use crate::random::bulk;
use crate::random::{RunKey, Source};

/// Marks an empty area.
const EMPTY: u32 = u32::MAX;
/// Marks an area taken by a coasting track (its slot in the low bits).
const TRACK: u32 = 1 << 31;
/// Counter offset of the dropout draws in a UAV's sensing stream (the noise uses the low ones).
const DROPOUT_DRAWS: u64 = 1 << 40;
/// Counter offset of the bad channel's loss draws in a UAV's radio stream.
const BURST_DRAWS: u64 = 1 << 40;

/// A radio message: its sender, the state it reports and where the sender was.
#[derive(Debug, Clone, Copy)]
pub struct Message {
    pub sender: u32,
    pub state: State9,
    pub at: [f64; 3],
}

/// What every UAV's update reads in one step.
pub struct View<'a> {
    pub c: &'a Consts,
    pub sc: &'a Scenario,
    pub states: &'a [State9],
    pub grid: &'a NeighbourGrid,
    pub run: RunKey,
    /// Step number of the draws.
    pub draw_step: u64,
    /// Step number of the tracks (negative in the warm-up).
    pub k: i32,
    /// The origin O(k) of the reference points, and O(0).
    pub origin: [f64; 3],
    pub origin0: [f64; 3],
    /// The origins of the last steps, O(k0) at `k0 mod len`.
    pub ring: &'a [[f64; 3]],
    pub messages: &'a [Message],
    /// Their index by sender position.
    pub reach: &'a crate::world::reach::Reach,
    /// Each UAV's environment (the position-fix bias), empty when the scenario has none.
    pub env: &'a [crate::world::environment::UavEnv],
    /// The warm-up: an ideal link (no dropout but the references' own, no loss).
    pub warm: bool,
}

impl View<'_> {
    /// `O(k0) − O(k)`: how far the reference points of recent step `k0` lie from this step's.
    #[inline]
    pub fn shift(&self, k0: i32) -> [f64; 3] {
        let o = self.ring[ring_index(k0, self.ring.len())];
        [o[0] - self.origin[0], o[1] - self.origin[1], o[2] - self.origin[2]]
    }
}

/// Where step `k` goes in a ring of `len` origins (a power of two).
#[inline]
pub fn ring_index(k: i32, len: usize) -> usize {
    (k as u32 as usize) & (len - 1)
}

/// Per-thread working memory, allocated once.
pub struct Scratch {
    best_d2: Vec<f64>,
    best_id: Vec<u32>,
    refs: Vec<u32>,
    close: Vec<u32>,
    /// Observed onboard (areas, references), then close-range detections.
    picked: Vec<u32>,
    heard: Vec<usize>,
    /// Messages within radio range (`Reach::for_each`).
    in_range: Vec<u32>,
    /// How many of `picked` were reported onboard (the rest are close-range detections).
    onboard: usize,
    normals: Vec<f32>,
    obs: Vec<Observation>,
    nearest: Vec<(u32, f32)>,
    avoid: Option<Avoidance>,
}

impl Scratch {
    pub fn new(c: &Consts) -> Self {
        Self {
            best_d2: vec![f64::INFINITY; c.areas],
            best_id: vec![0; c.areas],
            refs: Vec::with_capacity(8),
            close: Vec::with_capacity(8),
            picked: Vec::with_capacity(c.capacity + 8),
            heard: Vec::with_capacity(8),
            in_range: Vec::new(),
            onboard: 0,
            normals: Vec::with_capacity(9 * (c.capacity + 8)),
            obs: Vec::with_capacity(c.capacity + 8),
            nearest: vec![(EMPTY, 0.0); c.areas],
            avoid: c.avoid.map(|(d, a)| Avoidance::new(d, a)),
        }
    }
}

/// UAV `i`'s own measurement at this step (absolute): the truth plus noise from its own-state
/// stream, and in flight its position fix's bias. Its broadcasts carry the same measurement.
pub fn own_measurement(v: &View<'_>, i: usize) -> State9 {
    let mut z = [0.0f32; 9];
    bulk::normals(bulk::key(&v.run, i as u64, Source::OwnState, v.draw_step), 0, &mut z);
    let mut s = v.states[i];
    for k in 0..9 {
        s[k] += f64::from(v.c.sigma[k] * z[k]);
    }
    if let Some(e) = v.env.get(i).filter(|_| !v.warm) {
        for k in 0..3 {
            s[X + k] += e.gnss_bias[k];
        }
    }
    s
}

/// What UAV `i` decided and how: its input (applied) and its record.
pub struct Update {
    pub applied: [f32; 6],
    pub step: UavStep,
}

/// The update of follower `i`.
pub fn update(
    v: &View<'_>,
    i: usize,
    s: &mut Scratch,
    tracks: &mut Owner<'_>,
    kept: &mut Option<Box<Avoidance>>,
) -> Update {
    let c = v.c;
    let radio_used = perceive(v, i, s);
    let own_abs = own_measurement(v, i);
    // Positions relative to the reference point R_i(k) = O(k) + A_i, A_i = p_i(0) − O(0).
    let p0 = &v.sc.initial()[i];
    let r_i = [
        v.origin[0] + (p0[0] - v.origin0[0]),
        v.origin[1] + (p0[1] - v.origin0[1]),
        v.origin[2] + (p0[2] - v.origin0[2]),
    ];
    let mut own = own_abs;
    for k in 0..3 {
        own[k] -= r_i[k];
    }
    build_observations(v, i, s, &r_i);
    let d = decide(v, i, &own, s, tracks, kept);
    let mut step = UavStep { radio_used, ..UavStep::default() };
    let Some((outcome, input)) = d else {
        step.outcome = Some(StepOutcome::Alone);
        return Update { applied: [0.0; 6], step };
    };
    step.outcome = Some(outcome.into());
    step.effort = (0..6).map(|a| (input[a] / c.scale[a]).powi(2)).sum::<f64>().sqrt() as f32;
    let adjusted = matches!(outcome, Outcome::Adjusted { .. });
    let mut applied = input;
    if adjusted && c.actuation_error > 0.0 {
        let key = bulk::key(&v.run, i as u64, Source::Actuation, v.draw_step);
        for a in 0..6 {
            let e = 2.0 * bulk::uniform(key, a as u64) - 1.0;
            applied[a] = input[a] * (1.0 + c.actuation_error * e);
        }
        // The model error: the applied input's effect on the state minus the commanded one's.
        for a in 0..3 {
            let du = applied[a] - input[a];
            step.model_error[X + a] = (0.5 * c.dt * du) as f32;
            step.model_error[VX + a] = du as f32;
            step.model_error[ALPHA + a] = (applied[3 + a] - input[3 + a]) as f32;
        }
    }
    let mut out = [0.0f32; 6];
    for a in 0..6 {
        out[a] = applied[a] as f32;
    }
    Update { applied: out, step }
}

/// Whether an observation survives dropout `p` (draw `n` of the UAV's dropout draws).
#[inline]
fn kept(p: f64, key: u64, n: &mut u64) -> bool {
    if p <= 0.0 {
        return true;
    }
    *n += 1;
    bulk::uniform(key, DROPOUT_DRAWS + *n) >= p
}

/// Fills `s.picked` (onboard, then close-range) and `s.heard` (radio messages) for UAV `i`
/// from the true geometry; returns the radio messages it used.
fn perceive(v: &View<'_>, i: usize, s: &mut Scratch) -> u16 {
    let c = v.c;
    let me = &v.states[i];
    let p = [me[X], me[X + 1], me[X + 2]];
    let (sin_yaw, cos_yaw) = me[BETA].sin_cos();
    s.best_d2.iter_mut().for_each(|d| *d = f64::INFINITY);
    s.refs.clear();
    s.close.clear();
    s.picked.clear();
    s.heard.clear();
    let (best_d2, best_id, close) = (&mut s.best_d2, &mut s.best_id, &mut s.close);
    let states = v.states;
    v.grid.for_each_within(p, c.range, |j, q, d2| {
        if j as usize == i {
            return;
        }
        if c.watch.may_see(d2) {
            let o = &states[j as usize];
            let w = [o[VX] - me[VX], o[VX + 1] - me[VX + 1], o[VX + 2] - me[VX + 2]];
            if c.watch.sees(d2, [q[0] - p[0], q[1] - p[1], q[2] - p[2]], w) {
                close.push(j);
            }
        }
        let a = c.classifier.area(sin_yaw, cos_yaw, q[0] - p[0], q[1] - p[1]);
        let better = d2 < best_d2[a];
        best_id[a] = if better { j } else { best_id[a] };
        best_d2[a] = if better { d2 } else { best_d2[a] };
    });
    let deps = &v.sc.dependencies()[i];
    for &(id, _) in deps.refs() {
        let j = id.index();
        let Some(q) = v.states.get(j) else { continue };
        let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
        if j != i && d2 <= c.r2 {
            s.refs.push(id.0);
        }
    }
    s.refs.sort_unstable();
    let (dropout, ref_dropout) =
        if v.warm { (0.0, v.sc.reference_dropout_set().unwrap_or(0.0)) } else { (c.dropout, c.reference_dropout) };
    let drop_key = bulk::key(&v.run, i as u64, Source::Sensing, v.draw_step);
    let mut draws = 0;
    let loss = |j: u32| {
        if ref_dropout != dropout && deps.refs().iter().any(|r| r.0 .0 == j) {
            ref_dropout
        } else {
            dropout
        }
    };
    for a in 0..c.areas {
        if s.best_d2[a] < f64::INFINITY && kept(loss(s.best_id[a]), drop_key, &mut draws) {
            s.picked.push(s.best_id[a]);
        }
    }
    for r in 0..s.refs.len() {
        let j = s.refs[r];
        let in_area = (0..c.areas).any(|a| s.best_d2[a] < f64::INFINITY && s.best_id[a] == j);
        if !in_area && kept(ref_dropout, drop_key, &mut draws) {
            s.picked.push(j);
        }
    }
    let onboard = s.picked.len();
    // Radio: a message from a UAV perceived onboard adds nothing (α-β tracks do not fuse).
    let radio_key = bulk::key(&v.run, i as u64, Source::Radio, v.draw_step);
    let loss_p = if v.warm { 0.0 } else { c.radio_loss };
    // A receiver whose channel is in its bad state (bursty losses) loses each message with
    // `loss_bad` besides.
    let bad_p = match c.burst_loss {
        Some(p) if !v.warm && v.env.get(i).is_some_and(|e| e.channel_bad) => p,
        _ => 0.0,
    };
    let (picked, heard) = (&s.picked, &mut s.heard);
    v.reach.for_each(v.messages.len(), p, v.sc.radio().range_m, &mut s.in_range, |m_idx| {
        let m = &v.messages[m_idx];
        let j = m.sender;
        if j as usize == i || picked[..onboard].contains(&j) {
            return;
        }
        let d2 = (m.at[0] - p[0]).powi(2) + (m.at[1] - p[1]).powi(2) + (m.at[2] - p[2]).powi(2);
        if d2 > c.radio_range2
            || (loss_p > 0.0 && bulk::uniform(radio_key, m_idx as u64) < loss_p)
            || (bad_p > 0.0 && bulk::uniform(radio_key, BURST_DRAWS + m_idx as u64) < bad_p)
        {
            return;
        }
        heard.push(m_idx);
    });
    if !s.close.is_empty() {
        s.close.sort_unstable();
        for k in 0..s.close.len() {
            let j = s.close[k];
            if !s.picked[..onboard].contains(&j) && kept(dropout, drop_key, &mut draws) {
                s.picked.push(j);
            }
        }
    }
    s.onboard = onboard;
    if v.warm {
        0
    } else {
        s.heard.len() as u16
    }
}

/// Turns what was picked into observations relative to `r_i`, with noise drawn in one pass:
/// onboard reports, radio messages, close-range detections (the reference's order).
fn build_observations(v: &View<'_>, i: usize, s: &mut Scratch, r_i: &[f64; 3]) {
    let c = v.c;
    let onboard = s.onboard;
    let noisy = s.picked.len();
    s.normals.clear();
    s.normals.resize(9 * noisy, 0.0);
    bulk::normals(bulk::key(&v.run, i as u64, Source::Sensing, v.draw_step), 0, &mut s.normals);
    s.obs.clear();
    let observe = |j: u32, z: &[f32], source| {
        let mut st = v.states[j as usize];
        for k in 0..9 {
            st[k] += f64::from(c.sigma[k] * z[k]);
        }
        for k in 0..3 {
            st[k] -= r_i[k];
        }
        Observation { id: UavId(j), state: st, age_s: 0.0, source }
    };
    for (n, &j) in s.picked[..onboard].iter().enumerate() {
        s.obs.push(observe(j, &s.normals[9 * n..9 * n + 9], ObservationSource::Onboard));
    }
    for &m in &s.heard {
        let msg = &v.messages[m];
        let mut st = msg.state;
        for k in 0..3 {
            st[k] -= r_i[k];
        }
        s.obs.push(Observation { id: UavId(msg.sender), state: st, age_s: 0.0, source: ObservationSource::Radio });
    }
    for n in onboard..noisy {
        let j = s.picked[n];
        s.obs.push(observe(j, &s.normals[9 * n..9 * n + 9], ObservationSource::Close));
    }
}

/// Steps 1-3 accumulated (as in the reference controller), in f32 while summing.
struct Sums {
    bar: [f32; 9],
    w_bar: f32,
    n_bar: u16,
    dep: [f32; 9],
    c_sum: f32,
    main_refs: u16,
    push: [f64; 3],
}

/// The sums as the centre takes them.
struct Summed {
    bar: State9,
    w_bar: f64,
    n_bar: u16,
    dep: State9,
    c_sum: f64,
    main_refs: u16,
    push: [f64; 3],
}

impl Sums {
    fn new() -> Self {
        Self { bar: [0.0; 9], w_bar: 0.0, n_bar: 0, dep: [0.0; 9], c_sum: 0.0, main_refs: 0, push: [0.0; 3] }
    }

    /// A neighbour standing for its area, weight f.
    #[inline]
    fn add_bar(&mut self, f: f32, x_hat: &[f32; 9]) {
        for a in 0..9 {
            self.bar[a] += f * x_hat[a];
        }
        self.w_bar += f;
        self.n_bar += 1;
    }

    /// A main reference, weight c·f.
    #[inline]
    fn add_dep(&mut self, cf: f32, x_hat: &[f32; 9]) {
        for a in 0..9 {
            self.dep[a] += cf * x_hat[a];
        }
        self.c_sum += cf;
        self.main_refs += 1;
    }

    fn finish(self) -> Summed {
        Summed {
            bar: State9::from_fn(|a, _| f64::from(self.bar[a])),
            w_bar: f64::from(self.w_bar),
            n_bar: self.n_bar,
            dep: State9::from_fn(|a, _| f64::from(self.dep[a])),
            c_sum: f64::from(self.c_sum),
            main_refs: self.main_refs,
            push: self.push,
        }
    }
}

/// The controller's step for UAV `i` at its own estimate `own` (relative): None when it
/// perceives nothing (it flies on), else its outcome and input.
fn decide(
    v: &View<'_>,
    i: usize,
    own: &State9,
    s: &mut Scratch,
    tracks: &mut Owner<'_>,
    kept: &mut Option<Box<Avoidance>>,
) -> Option<(Outcome, [f64; 6])> {
    let c = v.c;
    let sc = v.sc;
    let formation = &**sc.formation();
    let me = UavId(i as u32);
    let slot_i = *formation.slot(me)?;
    let deps = &sc.dependencies()[i];
    let dt = c.dt;
    let k = v.k;
    let f = &c.filter;
    tracks.sweep(k, c.track_limit);
    let mut x_hold = *own;
    for a in 0..3 {
        x_hold[X + a] += dt * own[VX + a];
    }
    // §2: S_i, the nearest perceived UAV per area, in the UAV's own (noisy) view.
    let nearest = &mut s.nearest;
    nearest.iter_mut().for_each(|a| a.0 = EMPTY);
    let (sin_yaw, cos_yaw) = own[BETA].sin_cos();
    let obs = &s.obs;
    for (n, o) in obs.iter().enumerate() {
        if o.source == ObservationSource::Close || o.id == me {
            continue;
        }
        let (dx, dy, dz) = (o.state[X] - own[X], o.state[X + 1] - own[X + 1], o.state[X + 2] - own[X + 2]);
        let d2 = dx * dx + dy * dy + dz * dz;
        if o.source == ObservationSource::Onboard && d2 > c.r2 {
            continue;
        }
        let a = &mut nearest[c.classifier.area(sin_yaw, cos_yaw, dx, dy)];
        let d2 = d2 as f32;
        if a.0 == EMPTY || d2 < a.1 {
            *a = (n as u32, d2);
        }
    }
    // §3: neighbours perceived recently but not now coast into areas with no fresh report.
    let observed = |id: u32| obs.iter().any(|o| o.id.0 == id && o.source != ObservationSource::Close);
    // The neighbour of track `t` if it coasts now: the navigator, where the plan carries
    // reports, up to the track timeout (as the reference controller's `coast`).
    let coasting = |tracks: &Owner<'_>, t: usize| {
        let id = tracks.coasting(t, k, c.coast_steps.max(c.timeout_steps))?;
        let nav = c.plan_navigator == Some(id);
        (nav || tracks.age_steps(t, k) <= c.coast_steps).then_some(id)
    };
    for t in 0..tracks.used() {
        let Some(id) = coasting(tracks, t) else { continue };
        if id as usize == i || observed(id) {
            continue;
        }
        let h = tracks.age_steps(t, k) as f64 * dt;
        let x = tracks.state_at(f, t, h, v.shift(tracks.measured_at(t, k)));
        let (dx, dy, dz) = (f64::from(x[0]) - own[X], f64::from(x[1]) - own[X + 1], f64::from(x[2]) - own[X + 2]);
        let d2 = dx * dx + dy * dy + dz * dz;
        if d2 > c.r2 {
            continue;
        }
        let a = &mut nearest[c.classifier.area(sin_yaw, cos_yaw, dx, dy)];
        let d2 = d2 as f32;
        if a.0 == EMPTY || (a.0 & TRACK != 0 && d2 < a.1) {
            *a = (TRACK | t as u32, d2);
        }
    }
    // Steps 1-3: for each neighbour in S_i (then each main reference outside it), F·X_j from
    // its track and X̂_ij − X_hold = F·X_j + W_ij − X_hold (eq. 10), summed with the weights of
    // X̄_i and X̂ᴰ_i.
    let shifts = |k0: i32| v.shift(k0);
    let xh = super::tracks::to_f32(&x_hold);
    let mut e = Sums::new();
    let mut fed = 0;
    let coast = |tracks: &Owner<'_>, t: usize, id: u32| {
        let age = tracks.age_steps(t, k) as f64 * dt;
        let (k0, h) = (tracks.measured_at(t, k), age + dt);
        let x = match &c.carry {
            Some(carry) if h > dt.min(f.coast_accel_s) + proxform_core::predictor::SAME_INSTANT_S => {
                tracks.carried(f, carry, t, (f64::from(k0) * dt, h), shifts(k0))
            }
            _ => tracks.state_at(f, t, h, shifts(k0)),
        };
        let w = if c.plan_navigator == Some(id) { 1.0 } else { (-age / c.coast_decay_s).exp() as f32 };
        (x, w)
    };
    for a in 0..c.areas {
        let n = nearest[a].0;
        if n == EMPTY {
            continue;
        }
        let (id, f_x_j, w) = if n & TRACK != 0 {
            let t = (n & !TRACK) as usize;
            let Some(id) = coasting(tracks, t) else { continue };
            let (x, w) = coast(tracks, t, id);
            (id, x, w)
        } else {
            let o = &obs[n as usize];
            fed += 1;
            (o.id.0, tracks.predict(f, (o.id.0, fed - 1), k, &o.state, shifts).1, 1.0)
        };
        let Some(slot_j) = formation.slot(UavId(id)) else { continue };
        if c.separation > 0.0 {
            let p = [
                x_hold[X] - f64::from(f_x_j[0]),
                x_hold[X + 1] - f64::from(f_x_j[1]),
                x_hold[X + 2] - f64::from(f_x_j[2]),
            ];
            push_apart(p, c.separation, || Some((slot_j.offset_m - slot_i.offset_m).norm()), &mut e.push);
        }
        let x_hat = implied(c.course_frame, &slot_i, slot_j, &f_x_j, &xh);
        e.add_bar(w, &x_hat);
        if let Some(cd) = deps.degree(UavId(id)) {
            e.add_dep(cd as f32 * w, &x_hat);
        }
    }
    for r in 0..deps.refs().len() {
        let (id, cd) = deps.refs()[r];
        let (f_x_j, w) = match obs.iter().position(|o| o.id == id && o.source != ObservationSource::Close) {
            Some(n) => {
                if nearest.iter().any(|a| a.0 == n as u32) {
                    continue;
                }
                let o = &obs[n];
                let d2 = (0..3).map(|a| (o.state[a] - own[a]).powi(2)).sum::<f64>();
                if o.source == ObservationSource::Onboard && d2 > c.r2 {
                    continue;
                }
                fed += 1;
                (tracks.predict(f, (id.0, fed - 1), k, &o.state, shifts).1, 1.0)
            }
            None => {
                let Some(t) = (0..tracks.used()).find(|&t| coasting(tracks, t) == Some(id.0)) else {
                    continue;
                };
                if nearest.iter().any(|a| a.0 == TRACK | t as u32) {
                    continue;
                }
                coast(tracks, t, id.0)
            }
        };
        let Some(slot_j) = formation.slot(id) else { continue };
        let x_hat = implied(c.course_frame, &slot_i, slot_j, &f_x_j, &xh);
        e.add_dep(cd as f32 * w, &x_hat);
    }
    let e = e.finish();
    // Step 8: nothing perceived.
    if e.n_bar == 0 && e.main_refs == 0 {
        return None;
    }
    // Step 4: the envelope centre O_i − X_hold (the reference's own, from the averages).
    let x_bar = if e.n_bar > 0 { e.bar / e.w_bar } else { e.dep / e.c_sum };
    let x_hat_d = (e.main_refs > 0).then(|| e.dep / e.c_sum);
    let (mut o_i, goal) = centre_from(sc.controller(), &x_bar, x_hat_d.as_ref(), &e.push, c.stopping);
    // Collision avoidance: the reference's rule; a UAV's own copy only while it remembers.
    if c.avoid.is_some() {
        let params = sc.controller();
        let vehicle = sc.vehicle();
        match kept {
            Some(av) => {
                av.perceive(formation, me, &slot_i, &x_hold, params, &s.obs);
                av.limit(vehicle, &x_hold, dt, &mut o_i, &goal);
                if !av.remembers() {
                    *kept = None;
                }
            }
            // A UAV whose rule remembers nothing and that cannot bind leaves the centre as it
            // is: the rule need not run.
            None if !s
                .avoid
                .as_ref()
                .is_some_and(|av| av.may_bind(vehicle, &x_hold, dt, &o_i, &s.obs, params.track_timeout_s)) => {}
            None => {
                if let Some(av) = s.avoid.as_mut() {
                    av.perceive(formation, me, &slot_i, &x_hold, params, &s.obs);
                    av.limit(vehicle, &x_hold, dt, &mut o_i, &goal);
                    if av.remembers() {
                        *kept = Some(Box::new(av.clone()));
                        if let Some((d, acc)) = c.avoid {
                            *av = Avoidance::new(d, acc);
                        }
                    }
                }
            }
        }
    }
    // Steps 5-6: hold while X_hold − O_i lies inside the envelope.
    let normalised_sq: f64 = (0..9).map(|a| (o_i[a] * c.inv_threshold[a]).powi(2)).sum();
    if normalised_sq <= c.rho2 {
        return Some((Outcome::Held, [0.0; 6]));
    }
    // Step 7: the one-step input, r = X_hold − O_i.
    Some((Outcome::Adjusted { normalised_sq }, one_step_input(c, own, &-o_i)))
}

/// Step 7 on the kinematic vehicle: the input toward the target whose course-keeping
/// deviation is `r`, within the limits at `own`. Its cost Hessian is diagonal, so
/// `ControllerSetup::input_toward`'s solver takes one sweep: `u_a = clamp(−g_a/h_a)`, written
/// out here (tested against it).
fn one_step_input(c: &Consts, own: &State9, r: &State9) -> [f64; 6] {
    let (q, dt) = (&c.q, c.dt);
    let mut u = [0.0; 6];
    for a in 0..6 {
        let g =
            if a < 3 { 0.5 * dt * q[a] * r[a] + q[VX + a] * r[VX + a] } else { q[ALPHA + a - 3] * r[ALPHA + a - 3] };
        let vel = own[VX + a];
        let lo = (c.state_min[a] - vel).min(0.0).max(-c.scale[a]);
        let hi = (c.state_max[a] - vel).max(0.0).min(c.scale[a]);
        u[a] = if c.h[a] > 0.0 { (-g / c.h[a]).clamp(lo, hi) } else { 0.0 };
    }
    u
}

/// `X̂_ij − X_hold` (eq. 10): the neighbour's prediction plus `W_ij` (the slots' offset,
/// turned by j's course in a course frame, and attitude offset), minus X_hold, attitudes
/// wrapped.
#[inline]
fn implied(
    course_frame: bool,
    slot_i: &proxform_core::FormationSlot,
    slot_j: &proxform_core::FormationSlot,
    f_x_j: &[f32; 9],
    xh: &[f32; 9],
) -> [f32; 9] {
    let off = slot_i.offset_m - slot_j.offset_m;
    let att = slot_i.attitude_offset_rad - slot_j.attitude_offset_rad;
    let (cs, sn) = if course_frame {
        let (vx, vy) = (f_x_j[3], f_x_j[4]);
        let h = (vx * vx + vy * vy).sqrt();
        if h > 1e-9 {
            (vx / h, vy / h)
        } else {
            (1.0, 0.0)
        }
    } else {
        (1.0, 0.0)
    };
    let (ox, oy, oz) = (off.x as f32, off.y as f32, off.z as f32);
    let mut d = [0.0f32; 9];
    d[0] = f_x_j[0] - xh[0] + (cs * ox - sn * oy);
    d[1] = f_x_j[1] - xh[1] + (sn * ox + cs * oy);
    d[2] = f_x_j[2] - xh[2] + oz;
    for a in 3..6 {
        d[a] = f_x_j[a] - xh[a];
    }
    for a in 0..3 {
        d[6 + a] = super::tracks::wrap_pi(f_x_j[6 + a] - xh[6 + a] + att[a] as f32);
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_input_is_the_reference_solvers() {
        // Random deviations and states, near and beyond the limits: the same input as the
        // reference controller's solver.
        let sc = proxform_scenario::builtin::swarm(50).expect("valid");
        let c = Consts::new(&sc);
        let setup = sc.agents().controller();
        let mut seed = 99u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..2000 {
            let mut own = State9::zeros();
            let mut r = State9::zeros();
            for k in 0..9 {
                own[k] = [100.0, 100.0, 100.0, 160.0, 50.0, 40.0, 1.2, 0.6, 1.2][k] * next();
                r[k] = [20.0, 20.0, 20.0, 10.0, 10.0, 10.0, 0.2, 0.2, 0.2][k] * next();
            }
            own[VX] += 75.0;
            let want = setup.input_toward(&own, &r);
            let got = one_step_input(&c, &own, &r);
            for a in 0..6 {
                assert!((got[a] - want[a]).abs() <= 1e-12 * want[a].abs().max(1e-3), "{a}: {got:?} vs {want:?}");
            }
        }
    }
}
