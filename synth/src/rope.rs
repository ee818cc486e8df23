//! The rope: a chain of particles simulated with position-based dynamics
//! (stretch and bending distance constraints with compliance, gravity, table
//! contact with friction, damping, optional self-contact), any particle
//! grasped and moved along a path. World frame: table plane z = 0, z up.

use alloc::vec;
use alloc::vec::Vec;

use upetrack::math::{self, Vec3};
use upetrack::polyline::resample_uniform;

/// Physical settings of a rope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RopeSettings {
    /// Length, metres. Default 0.8 (the paper's cotton rope).
    pub length: f64,
    /// Thickness (diameter), metres. Default 0.015.
    pub thickness: f64,
    /// Number of particles. Default 81 (10 mm segments).
    pub particles: usize,
    /// Bending compliance (inverse stiffness) of the (i, i+2) constraints; larger is softer. Default 2e-4.
    pub bending_compliance: f64,
    /// Friction coefficient with the table. Default 0.8 (cotton on wood).
    pub friction: f64,
    /// Velocity damping per second. Default 2.
    pub damping: f64,
    /// Keep non-neighbouring segments at least a thickness apart. Default true.
    pub self_contact: bool,
    /// Substeps per frame. Default 20.
    pub substeps: usize,
}

impl Default for RopeSettings {
    fn default() -> Self {
        Self {
            length: 0.8,
            thickness: 0.015,
            particles: 81,
            bending_compliance: 2e-4,
            friction: 0.8,
            damping: 2.0,
            self_contact: true,
            substeps: 20,
        }
    }
}

/// Another rope as an obstacle for one step ([`Rope::step_among`]).
#[derive(Debug, Clone, Copy)]
pub struct Obstacle<'a> {
    /// Its particles, world frame, metres.
    pub particles: &'a [Vec3],
    /// Its radius, metres.
    pub radius: f64,
}

/// Gravity, m/s^2.
const GRAVITY: f64 = 9.81;

/// The simulated rope.
#[derive(Debug, Clone)]
pub struct Rope {
    /// Settings.
    pub settings: RopeSettings,
    /// Particle positions, world frame, metres.
    pub x: Vec<Vec3>,
    v: Vec<Vec3>,
    rest: f64,
    /// Grasped particles and their current targets.
    grasps: Vec<(usize, Vec3)>,
}

impl Rope {
    /// A rope laid along the polyline `shape` (world frame), scaled about its
    /// centroid to the rope's length and lowered to rest on the table.
    pub fn laid_along(shape: &[Vec3], settings: RopeSettings) -> Self {
        let n = settings.particles.max(3);
        let mut dense = resample_uniform(shape, 2000);
        let c = dense.iter().sum::<Vec3>() / dense.len().max(1) as f64;
        for p in dense.iter_mut() {
            p.z = 0.0;
        }
        // Scale about the centroid until the particle chain (chords, not the
        // curve) has the rope's length.
        let mut x = resample_uniform(&dense, n);
        for _ in 0..4 {
            let len = upetrack::polyline::polyline_length(&x).max(1e-9);
            let s = settings.length / len;
            for p in dense.iter_mut() {
                *p = c + (*p - c) * s;
            }
            x = resample_uniform(&dense, n);
        }
        for p in x.iter_mut() {
            p.z = settings.thickness / 2.0;
        }
        Self {
            rest: settings.length / (n - 1) as f64,
            v: vec![Vec3::zeros(); n],
            x,
            grasps: Vec::new(),
            settings,
        }
    }

    /// Rope radius, metres.
    pub fn radius(&self) -> f64 {
        self.settings.thickness / 2.0
    }

    /// Holds particle `i` at `target` (replacing an earlier grasp of it).
    pub fn grasp(&mut self, i: usize, target: Vec3) {
        self.grasps.retain(|g| g.0 != i);
        if i < self.x.len() {
            self.grasps.push((i, target));
        }
    }

    /// Releases every grasp.
    pub fn release_all(&mut self) {
        self.grasps.clear();
    }

    /// Current length of the particle chain, metres.
    pub fn current_length(&self) -> f64 {
        upetrack::polyline::polyline_length(&self.x)
    }

    fn solve_distance(
        p: &mut [Vec3],
        w: &[f64],
        i: usize,
        j: usize,
        rest: f64,
        alpha: f64,
        lambda: &mut f64,
    ) {
        let d = p[j] - p[i];
        let len = math::norm(&d);
        let wsum = w[i] + w[j];
        if len < 1e-12 || wsum == 0.0 {
            return;
        }
        let c = len - rest;
        let dl = (-c - alpha * *lambda) / (wsum + alpha);
        *lambda += dl;
        let corr = d / len * dl;
        p[i] -= corr * w[i];
        p[j] += corr * w[j];
    }

    /// Advances the simulation by `dt` seconds. Grasped particles move
    /// linearly from their position to their target over the step.
    pub fn step(&mut self, dt: f64) {
        self.step_among(dt, &[]);
    }

    /// [`Rope::step`] beside other ropes, held where they are for this
    /// step: each is a chain of particles of a radius (another rope's `x`
    /// and [`Rope::radius`]) that this rope's particles are kept out of, so
    /// that ropes lie on each other instead of through. Stepping the ropes
    /// of a scene one after the other makes them push each other.
    pub fn step_among(&mut self, dt: f64, others: &[Obstacle<'_>]) {
        let n = self.x.len();
        let sub = self.settings.substeps.max(1);
        let h = dt / sub as f64;
        let r = self.radius();
        let mut w = vec![1.0; n];
        let starts: Vec<(usize, Vec3, Vec3)> = self
            .grasps
            .iter()
            .map(|&(i, t)| (i, self.x[i], t))
            .collect();
        for &(i, _, _) in &starts {
            w[i] = 0.0;
        }
        let damp = 1.0 / (1.0 + self.settings.damping * h);
        let alpha_stretch = 0.0;
        let alpha_bend = self.settings.bending_compliance / (h * h);
        let mut p = self.x.clone();
        let mut lambda_s = vec![0.0; n];
        let mut lambda_b = vec![0.0; n];
        let mut scratch = Projection::default();
        for s in 1..=sub {
            let frac = s as f64 / sub as f64;
            for i in 0..n {
                if w[i] > 0.0 {
                    self.v[i].z -= GRAVITY * h;
                    self.v[i] *= damp;
                    p[i] = self.x[i] + self.v[i] * h;
                }
            }
            for &(i, a, b) in &starts {
                p[i] = a + (b - a) * frac;
            }
            lambda_s.fill(0.0);
            lambda_b.fill(0.0);
            for i in 0..n - 1 {
                Self::solve_distance(
                    &mut p,
                    &w,
                    i,
                    i + 1,
                    self.rest,
                    alpha_stretch,
                    &mut lambda_s[i],
                );
            }
            for i in (0..n - 1).rev() {
                let mut l = 0.0;
                Self::solve_distance(&mut p, &w, i, i + 1, self.rest, alpha_stretch, &mut l);
            }
            for i in 0..n.saturating_sub(2) {
                Self::solve_distance(
                    &mut p,
                    &w,
                    i,
                    i + 2,
                    2.0 * self.rest,
                    alpha_bend,
                    &mut lambda_b[i],
                );
            }
            if self.settings.self_contact {
                self.self_contact(&mut p, &w);
            }
            for other in others {
                Self::keep_out(&mut p, &w, r, other);
            }
            // Table contact with Coulomb-like friction on the step's displacement.
            for i in 0..n {
                if w[i] == 0.0 || p[i].z >= r {
                    continue;
                }
                let pen = r - p[i].z;
                p[i].z = r;
                let mut dxy = p[i] - self.x[i];
                dxy.z = 0.0;
                let slide = math::norm(&dxy);
                let mu = self.settings.friction;
                if slide < mu * pen * 4.0 {
                    p[i].x = self.x[i].x;
                    p[i].y = self.x[i].y;
                } else if slide > 0.0 {
                    let keep = 1.0 - (mu * pen / slide).min(1.0);
                    p[i].x = self.x[i].x + dxy.x * keep;
                    p[i].y = self.x[i].y + dxy.y * keep;
                }
            }
            // Friction pins particles after the stretch passes have moved
            // them, so tension is lost to it: the chain's lengths are
            // projected back last, exactly, so that the rope does not stretch.
            project_lengths(&mut p, &w, self.rest, &mut scratch);
            for q in p.iter_mut() {
                q.z = q.z.max(r);
            }
            for i in 0..n {
                self.v[i] = (p[i] - self.x[i]) / h;
                self.x[i] = p[i];
            }
        }
    }

    /// Moves particles that are inside `other`'s particles (closer than the
    /// two radii) out along the line between them.
    fn keep_out(p: &mut [Vec3], w: &[f64], r: f64, other: &Obstacle<'_>) {
        let min = r + other.radius;
        for (pi, _) in p.iter_mut().zip(w).filter(|(_, w)| **w > 0.0) {
            for q in other.particles {
                let d = *pi - q;
                let len = math::norm(&d);
                if len < min && len > 1e-12 {
                    *pi = q + d * (min / len);
                }
            }
        }
    }

    /// Pushes apart particles closer than a thickness that are not within a
    /// few links of each other along the rope.
    fn self_contact(&self, p: &mut [Vec3], w: &[f64]) {
        let n = p.len();
        let min = self.settings.thickness;
        let skip = libm::ceil(min / self.rest) as usize + 1;
        for i in 0..n {
            for j in i + skip..n {
                let d = p[j] - p[i];
                let len = math::norm(&d);
                let wsum = w[i] + w[j];
                if len >= min || len < 1e-12 || wsum == 0.0 {
                    continue;
                }
                let corr = d / len * ((min - len) / wsum);
                p[i] -= corr * w[i];
                p[j] += corr * w[j];
            }
        }
    }
}

/// Relative error of a link at which [`project_lengths`] stops.
const PROJECTION_TOLERANCE: f64 = 1e-10;

/// Most Newton steps of [`project_lengths`]: each about squares the links'
/// relative error, so a substep's pull (well under a link) takes two or
/// three, and even a link a third off its length converges in eight.
const PROJECTION_MAX_STEPS: usize = 8;

/// Buffers of [`project_lengths`], kept across substeps.
#[derive(Debug, Default)]
struct Projection {
    /// Unit direction of each link.
    dir: Vec<Vec3>,
    /// Right-hand side, then the multipliers.
    rhs: Vec<f64>,
    /// Diagonal, then the forward sweep's modified diagonal.
    diag: Vec<f64>,
    /// Off-diagonal coupling of link `i` and link `i + 1`.
    off: Vec<f64>,
}

/// Puts every link of the chain `p` back to the length `rest` by the
/// smallest mass-weighted move (inverse masses `w`, 0 for a held particle):
/// the "fast projection" of Goldenthal et al. (2007). The links' linearised
/// constraints couple only neighbours, so each Newton step solves a
/// tridiagonal system in one forward and one backward sweep; Gauss-Seidel
/// passes would need on the order of the particle count to carry a pull
/// down the rope.
fn project_lengths(p: &mut [Vec3], w: &[f64], rest: f64, s: &mut Projection) {
    let m = p.len().saturating_sub(1);
    if m == 0 {
        return;
    }
    for _ in 0..PROJECTION_MAX_STEPS {
        s.dir.clear();
        s.rhs.clear();
        s.diag.clear();
        s.off.clear();
        let mut worst: f64 = 0.0;
        for i in 0..m {
            let d = p[i + 1] - p[i];
            let len = math::norm(&d);
            let wsum = w[i] + w[i + 1];
            if len < 1e-12 || wsum == 0.0 {
                // A link that cannot move is left out: its row is the identity.
                s.dir.push(Vec3::zeros());
                s.rhs.push(0.0);
                s.diag.push(1.0);
            } else {
                s.dir.push(d / len);
                s.rhs.push(rest - len);
                s.diag.push(wsum);
                worst = worst.max((rest - len).abs());
            }
        }
        if worst <= PROJECTION_TOLERANCE * rest {
            return;
        }
        for i in 0..m - 1 {
            // Links i and i + 1 share particle i + 1.
            s.off.push(-w[i + 1] * s.dir[i].dot(&s.dir[i + 1]));
        }
        // Thomas algorithm; the system is symmetric positive definite.
        for i in 1..m {
            let f = s.off[i - 1] / s.diag[i - 1];
            s.diag[i] -= f * s.off[i - 1];
            s.rhs[i] -= f * s.rhs[i - 1];
        }
        s.rhs[m - 1] /= s.diag[m - 1];
        for i in (0..m - 1).rev() {
            s.rhs[i] = (s.rhs[i] - s.off[i] * s.rhs[i + 1]) / s.diag[i];
        }
        for i in 0..=m {
            let mut dp = Vec3::zeros();
            if i < m {
                dp -= s.dir[i] * s.rhs[i];
            }
            if i > 0 {
                dp += s.dir[i - 1] * s.rhs[i - 1];
            }
            p[i] += dp * w[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rope_settles_on_the_table_and_keeps_its_length() {
        let shape: Vec<Vec3> = (0..100)
            .map(|i| {
                let t = i as f64 / 99.0;
                Vec3::new(
                    -0.2 + 0.4 * t,
                    0.1 * libm::sin(core::f64::consts::TAU * t),
                    0.05,
                )
            })
            .collect();
        let mut rope = Rope::laid_along(&shape, RopeSettings::default());
        assert!((rope.current_length() - 0.8).abs() < 1e-6);
        for _ in 0..60 {
            rope.step(1.0 / 30.0);
        }
        for p in &rope.x {
            assert!(
                (p.z - rope.radius()).abs() < 1e-3,
                "particle at z = {}",
                p.z
            );
        }
        let err = (rope.current_length() - 0.8).abs() / 0.8;
        assert!(err < 0.02, "length changed by {:.2} %", err * 100.0);
        // Pull one end 10 cm; the chain follows without stretching.
        for k in 1..=30 {
            let target = Vec3::new(0.2 + 0.1 * k as f64 / 30.0, 0.0, 0.0075);
            rope.grasp(80, target);
            rope.step(1.0 / 30.0);
            let err = (rope.current_length() - 0.8).abs() / 0.8;
            assert!(
                err < 1e-6,
                "length changed by {:.4} % while pulled (step {k})",
                err * 100.0
            );
        }
        assert!((rope.x[80].x - 0.3).abs() < 1e-9);
    }

    #[test]
    fn a_pull_against_table_friction_does_not_stretch_the_rope() {
        // A curved rope at rest, its end pulled fast along the rope: friction
        // pins the particles behind the stretch passes, which stretched the
        // drawn ropes by up to 7 % before the exact projection.
        let shape: Vec<Vec3> = (0..100)
            .map(|i| {
                let t = i as f64 / 99.0;
                let a = core::f64::consts::PI * t;
                Vec3::new(0.2 * libm::cos(a), 0.2 * libm::sin(a), 0.0)
            })
            .collect();
        let mut rope = Rope::laid_along(&shape, RopeSettings::default());
        for _ in 0..30 {
            rope.step(1.0 / 30.0);
        }
        let start = rope.x[80];
        let along = (rope.x[80] - rope.x[79]) / math::norm(&(rope.x[80] - rope.x[79]));
        for k in 1..=15 {
            rope.grasp(80, start + along * (0.15 * k as f64 / 15.0));
            rope.step(1.0 / 30.0);
            for (i, link) in rope.x.windows(2).enumerate() {
                let l = math::norm(&(link[1] - link[0]));
                assert!(
                    (l - rope.rest).abs() < 1e-6 * rope.rest,
                    "link {i} is {:.6} of its rest length at step {k}",
                    l / rope.rest
                );
            }
        }
    }

    #[test]
    fn the_projection_keeps_held_particles_and_restores_every_link() {
        let mut p: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(0.1 * i as f64, 0.0, 0.0))
            .collect();
        p[5].x += 0.03;
        p[2].y += 0.02;
        let mut w = vec![1.0; 6];
        w[5] = 0.0;
        let held = p[5];
        project_lengths(&mut p, &w, 0.1, &mut Projection::default());
        assert_eq!(p[5], held);
        for link in p.windows(2) {
            assert!((math::norm(&(link[1] - link[0])) - 0.1).abs() < 1e-9);
        }
        // Two held neighbours: their link is left as it is, the rest solved.
        w[4] = 0.0;
        p[4].x -= 0.05;
        project_lengths(&mut p, &w, 0.1, &mut Projection::default());
        for link in p[..5].windows(2) {
            assert!((math::norm(&(link[1] - link[0])) - 0.1).abs() < 1e-9);
        }
    }
}
