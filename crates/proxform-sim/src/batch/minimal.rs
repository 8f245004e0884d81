//! The minimal-law limit that `proxform bench` measures beside the engines: a formation update
//! with as little work per UAV as a neighbour-based law can do, over the swarm scenario's slots.
//! It is not the method (no noise, no areas, no tracks, no envelope, no metrics): it is the floor
//! the method's cost per update is compared against.
//!
//! Each step: a uniform grid rebuilt by counting sort (cells of the sensing range), then for
//! every UAV the 8 nearest neighbours in the 3 × 3 cells around it, the slot-implied position
//! `p_j + d_i − d_j` averaged with weights `1/d`, and a velocity toward it clamped to the
//! vehicle's acceleration, in f32 structure-of-arrays form.

use rayon::prelude::*;

/// Neighbours each UAV averages over.
const NEAREST: usize = 8;

/// A swarm flying the minimal law.
#[derive(Debug, Clone)]
pub struct MinimalLaw {
    pos: Vec<[f32; 3]>,
    vel: Vec<[f32; 3]>,
    next: Vec<[f32; 3]>,
    slot: Vec<[f32; 3]>,
    /// UAV indices sorted by cell, and where each cell starts in that order.
    order: Vec<u32>,
    start: Vec<u32>,
    cell_of: Vec<u32>,
    cell: f32,
    nx: usize,
    ny: usize,
    origin: [f32; 2],
    dt: f32,
    accel: f32,
    parallel: bool,
}

impl MinimalLaw {
    /// UAVs at `slots` (formation offsets: forward, left, up; m), flying along x at `speed`
    /// (m/s), sensing within `range` (m), Δt `dt` (s), acceleration limit `accel` (m/s²); each
    /// starts off its slot by a deterministic few metres so that the law has work to do.
    pub fn new(slots: &[[f64; 3]], speed: f64, range: f64, dt: f64, accel: f64) -> Self {
        let n = slots.len();
        let slot: Vec<[f32; 3]> = slots.iter().map(|s| s.map(|v| v as f32)).collect();
        let pos = slot
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let wobble = ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32 / (1u64 << 24) as f32;
                [s[0] + 4.0 * (wobble - 0.5), s[1] - 3.0 * (wobble - 0.5), s[2]]
            })
            .collect();
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for s in &slot {
            for k in 0..2 {
                lo[k] = lo[k].min(s[k]);
                hi[k] = hi[k].max(s[k]);
            }
        }
        let cell = range as f32;
        // Room for the swarm to drift by a few cells before the grid must grow.
        let margin = 4.0 * cell;
        let origin = [lo[0] - margin, lo[1] - margin];
        let nx = (((hi[0] - lo[0] + 2.0 * margin) / cell) as usize + 1).max(1);
        let ny = (((hi[1] - lo[1] + 2.0 * margin) / cell) as usize + 1).max(1);
        Self {
            pos,
            vel: vec![[speed as f32, 0.0, 0.0]; n],
            next: vec![[0.0; 3]; n],
            slot,
            order: vec![0; n],
            start: vec![0; nx * ny + 1],
            cell_of: vec![0; n],
            cell,
            nx,
            ny,
            origin,
            dt: dt as f32,
            accel: accel as f32,
            parallel: n >= 1024,
        }
    }

    /// Forces serial or parallel stepping.
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.parallel = parallel;
        self
    }

    /// Bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.pos.len() * (4 * 12 + 8) + self.start.len() * 4
    }

    /// One step of every UAV.
    pub fn step(&mut self) {
        // The grid moves with the swarm's lead (UAV 0, flying along x): cells relative to it.
        let shift = self.pos[0][0] - self.slot[0][0];
        let (nx, ny, cell) = (self.nx, self.ny, self.cell);
        let origin = [self.origin[0] + shift, self.origin[1]];
        for (c, p) in self.cell_of.iter_mut().zip(&self.pos) {
            let cx = (((p[0] - origin[0]) / cell) as usize).min(nx - 1);
            let cy = (((p[1] - origin[1]) / cell) as usize).min(ny - 1);
            *c = (cy * nx + cx) as u32;
        }
        self.start.iter_mut().for_each(|s| *s = 0);
        for &c in &self.cell_of {
            self.start[c as usize + 1] += 1;
        }
        for k in 1..self.start.len() {
            self.start[k] += self.start[k - 1];
        }
        let mut fill = self.start.clone();
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.order[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        let Self { pos, vel, next, slot, order, start, cell_of, dt, accel, .. } = self;
        let (pos, vel, slot, order, start, cell_of) = (&*pos, &*vel, &*slot, &*order, &*start, &*cell_of);
        let (dt, accel) = (*dt, *accel);
        let lead_vel = vel[0];
        let r2 = cell * cell;
        let one = |i: usize, out: &mut [f32; 3]| {
            let p = pos[i];
            let c = cell_of[i] as usize;
            let (cx, cy) = (c % nx, c / nx);
            let mut best_d2 = [f32::INFINITY; NEAREST];
            let mut best_j = [0u32; NEAREST];
            for y in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
                let a = start[y * nx + cx.saturating_sub(1)] as usize;
                let b = start[y * nx + (cx + 1).min(nx - 1) + 1] as usize;
                for &j in &order[a..b] {
                    let q = pos[j as usize];
                    let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                    if j as usize == i || d2 > r2 || d2 >= best_d2[NEAREST - 1] {
                        continue;
                    }
                    // Insert into the sorted list of the nearest.
                    let mut k = NEAREST - 1;
                    while k > 0 && best_d2[k - 1] > d2 {
                        best_d2[k] = best_d2[k - 1];
                        best_j[k] = best_j[k - 1];
                        k -= 1;
                    }
                    best_d2[k] = d2;
                    best_j[k] = j;
                }
            }
            let mut target = [0.0f32; 3];
            let mut w_sum = 0.0f32;
            for k in 0..NEAREST {
                if best_d2[k] == f32::INFINITY {
                    break;
                }
                let j = best_j[k] as usize;
                let w = 1.0 / best_d2[k].sqrt().max(1.0);
                for a in 0..3 {
                    target[a] += w * (pos[j][a] + slot[i][a] - slot[j][a]);
                }
                w_sum += w;
            }
            let v = vel[i];
            if w_sum == 0.0 {
                *out = v;
                return;
            }
            for a in 0..3 {
                let want = lead_vel[a] + (target[a] / w_sum - p[a]) / 2.0;
                out[a] = v[a] + (want - v[a]).clamp(-accel * dt, accel * dt);
            }
        };
        if self.parallel {
            next.par_iter_mut().enumerate().for_each(|(i, out)| one(i, out));
        } else {
            next.iter_mut().enumerate().for_each(|(i, out)| one(i, out));
        }
        for ((p, v), n) in self.pos.iter_mut().zip(self.vel.iter_mut()).zip(&self.next) {
            for a in 0..3 {
                p[a] += 0.5 * dt * (v[a] + n[a]);
            }
            *v = *n;
        }
    }

    /// The largest distance of any UAV from where its slot puts it relative to UAV 0 (m).
    pub fn largest_slot_error(&self) -> f32 {
        let (p0, s0) = (self.pos[0], self.slot[0]);
        self.pos
            .iter()
            .zip(&self.slot)
            .map(|(p, s)| (0..3).map(|a| (p[a] - p0[a] - (s[a] - s0[a])).powi(2)).sum::<f32>().sqrt())
            .fold(0.0, f32::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_minimal_law_pulls_a_lattice_into_its_slots() {
        let slots: Vec<[f64; 3]> = (0..400).map(|k| [-50.0 * (k / 20) as f64, 50.0 * (k % 20) as f64, 0.0]).collect();
        let mut law = MinimalLaw::new(&slots, 70.0, 80.0, 0.1, 5.0).with_parallel(false);
        let before = law.largest_slot_error();
        for _ in 0..300 {
            law.step();
        }
        let after = law.largest_slot_error();
        assert!(before > 1.0 && after < 0.3 * before, "{before} -> {after}");
        // Serial and parallel steps agree bit for bit (each UAV's update reads the old arrays).
        let mut a = MinimalLaw::new(&slots, 70.0, 80.0, 0.1, 5.0).with_parallel(false);
        let mut b = MinimalLaw::new(&slots, 70.0, 80.0, 0.1, 5.0).with_parallel(true);
        for _ in 0..20 {
            a.step();
            b.step();
        }
        assert_eq!(a.pos, b.pos);
    }
}
