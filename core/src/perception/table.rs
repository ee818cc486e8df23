//! The table the rope lies on: a plane fitted to the depth image outside
//! the rope (CDCPD2's table constraint, and where a rope that came out from
//! under an occluder must lie).

use alloc::vec::Vec;

use crate::math::Vec3;
use crate::perception::camera::depth_noise;
use crate::perception::evidence::{Evidence, OCCLUDER_MARGIN};

/// Pixels of the image sampled along each side for the table plane fit.
pub const PLANE_SAMPLES_PER_SIDE: usize = 40;
/// Iterations of the plane fit, each dropping points beyond `PLANE_INLIER` of it.
pub const PLANE_FIT_ROUNDS: usize = 3;
/// Distance from the plane within which a sample counts as table, metres.
pub const PLANE_INLIER: f64 = 0.01;
/// Fewest samples a plane is fitted to.
pub const MIN_PLANE_SAMPLES: usize = 30;

/// A plane `normal . p = offset`, the normal towards the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Plane {
    /// Unit normal, pointing to the camera's side.
    pub normal: Vec3,
    /// `normal . p` for points on the plane.
    pub offset: f64,
}

/// Share of a rope's points that must lie on a plane for it to rest there
/// ([`Plane::carries`]): nine in ten, so one lifted end or a noisy node
/// does not unseat it, a rope lifted or hanging does.
pub const RESTING_SHARE: f64 = 0.9;

/// Depth deviations (at the plane's depth) within which a measured pixel
/// counts as showing the plane ([`Plane::hides_inside`]).
pub const ON_PLANE_SIGMAS: f64 = 3.0;

impl Plane {
    /// Height of `p` above the plane, metres (negative behind it).
    pub fn height(&self, p: &Vec3) -> f64 {
        self.normal.dot(p) - self.offset
    }

    /// `true` when a rope of radius `radius` whose axis runs through `line`
    /// (three points or more) rests on the plane along its length: at least
    /// [`RESTING_SHARE`] of its points lie a radius above it within
    /// [`OCCLUDER_MARGIN`] (the depth a surface must be nearer by to hide
    /// a rope).
    pub fn carries(&self, line: &[Vec3], radius: f64) -> bool {
        if line.len() < 3 {
            return false;
        }
        let on = line
            .iter()
            .filter(|p| libm::fabs(self.height(p) - radius) <= OCCLUDER_MARGIN)
            .count();
        on as f64 >= RESTING_SHARE * line.len() as f64
    }

    /// `true` when `p` lies inside the plane's surface where the images
    /// show that surface: the pixel `p` projects to measures a depth on the
    /// plane (within [`OCCLUDER_MARGIN`] and [`ON_PLANE_SIGMAS`] deviations
    /// of depth noise) and `p` lies more than [`OCCLUDER_MARGIN`] behind the
    /// plane along its ray. There the surface is nearer than `p`, so the
    /// window test of [`Evidence::sight`] would say it hides `p`; but no
    /// rope can be inside the table it rests on.
    pub fn hides_inside(&self, evidence: &Evidence<'_>, p: &Vec3) -> bool {
        let Some(measured) = evidence.depth_at_point(p) else {
            return false;
        };
        // The plane along p's ray: the point s p with normal . (s p) = offset.
        let along = self.normal.dot(p);
        if !(p.z > 0.0) || !(libm::fabs(along) > 0.0) {
            return false;
        }
        let plane_z = p.z * self.offset / along;
        if !(plane_z > 0.0) {
            return false;
        }
        let focal = 0.5 * (evidence.camera.fx + evidence.camera.fy);
        let tolerance = OCCLUDER_MARGIN + ON_PLANE_SIGMAS * depth_noise(plane_z, focal);
        libm::fabs(measured - plane_z) < tolerance && p.z > plane_z + OCCLUDER_MARGIN
    }
}

/// The table: a plane fitted by least squares to depth pixels outside the
/// rope mask on a grid over the image, refitted twice to the samples
/// within a centimetre of it. `None` without enough samples.
pub fn fit_table(evidence: &Evidence<'_>) -> Option<Plane> {
    let f = evidence.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let mut pts = Vec::new();
    for j in 0..PLANE_SAMPLES_PER_SIDE {
        for i in 0..PLANE_SAMPLES_PER_SIDE {
            let u = (i * w + w / 2) / PLANE_SAMPLES_PER_SIDE;
            let v = (j * h + h / 2) / PLANE_SAMPLES_PER_SIDE;
            let raw = f.depth[v * w + u];
            if raw == 0 || evidence.mask.get(u as i64, v as i64) {
                continue;
            }
            pts.push(
                evidence
                    .camera
                    .deproject(u as f64, v as f64, raw as f64 * f.depth_scale),
            );
        }
    }
    let mut plane = None;
    for _ in 0..PLANE_FIT_ROUNDS {
        let used: Vec<Vec3> = match plane {
            None => pts.clone(),
            Some(Plane { normal, offset }) => pts
                .iter()
                .copied()
                .filter(|p: &Vec3| (normal.dot(p) - offset).abs() < PLANE_INLIER)
                .collect(),
        };
        if used.len() < MIN_PLANE_SAMPLES {
            return plane;
        }
        let c = used.iter().sum::<Vec3>() / used.len() as f64;
        let mut cov = nalgebra::Matrix3::<f64>::zeros();
        for p in &used {
            let d = p - c;
            cov += d * d.transpose();
        }
        let eig = cov.symmetric_eigen();
        let k = (0..3)
            .min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))
            .unwrap_or(2);
        let mut n: Vec3 = eig.eigenvectors.column(k).into_owned();
        // Towards the camera (the origin).
        if n.dot(&c) > 0.0 {
            n = -n;
        }
        plane = Some(Plane {
            normal: n,
            offset: n.dot(&c),
        });
    }
    plane
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::evidence::fixture::Table;

    /// A flat table 0.6 m away seen straight on by an 80 x 40 camera of
    /// focal 40 px, its plane, and a point `z` metres away at pixel (40, 20).
    fn flat() -> (Table, Plane) {
        let t = Table::new(80, 40, 40.0, 600);
        let plane = Plane {
            normal: Vec3::new(0.0, 0.0, -1.0),
            offset: -0.6,
        };
        (t, plane)
    }

    #[test]
    fn a_point_inside_the_table_where_the_table_is_seen_is_inside_it() {
        let (t, plane) = flat();
        let frame = t.frame();
        let e = t.evidence(&frame, &[], 0.0075);
        let p = |z: f64| t.at(40.0, 20.0, z);
        assert!(plane.hides_inside(&e, &p(0.62)));
        // Within the margin, on the table, or in front of it: not inside.
        assert!(!plane.hides_inside(&e, &p(0.6 + 0.8 * OCCLUDER_MARGIN)));
        assert!(!plane.hides_inside(&e, &p(0.5925)));
        // A box 15 cm above the table at that pixel hides it (more than the
        // depth noise of this 40 px camera): not the table.
        let mut boxed = Table::new(80, 40, 40.0, 600);
        boxed.depth[20 * 80 + 40] = 450;
        let frame = boxed.frame();
        assert!(!plane.hides_inside(&boxed.evidence(&frame, &[], 0.0075), &p(0.62)));
        // No depth there, out of view, behind the camera: nothing known.
        let mut hole = Table::new(80, 40, 40.0, 600);
        hole.depth[20 * 80 + 40] = 0;
        let frame = hole.frame();
        assert!(!plane.hides_inside(&hole.evidence(&frame, &[], 0.0075), &p(0.62)));
        let frame = t.frame();
        let e = t.evidence(&frame, &[], 0.0075);
        assert!(!plane.hides_inside(&e, &t.at(400.0, 20.0, 0.62)));
        assert!(!plane.hides_inside(&e, &Vec3::new(0.0, 0.0, -0.62)));
        assert!(!plane.hides_inside(&e, &Vec3::new(f64::NAN, 0.0, 0.62)));
    }

    #[test]
    fn a_rope_rests_on_a_plane_only_along_nine_tenths_of_its_length() {
        let (_, plane) = flat();
        let r = 0.0075;
        let on: Vec<Vec3> = (0..10)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.6 - r))
            .collect();
        assert!(plane.carries(&on, r));
        let mut one_lifted = on.clone();
        one_lifted[9].z -= 0.03;
        assert!(plane.carries(&one_lifted, r));
        let mut two_lifted = one_lifted.clone();
        two_lifted[8].z -= 0.03;
        assert!(!plane.carries(&two_lifted, r));
        assert!(!plane.carries(&on[..2], r));
        let mut nan = on.clone();
        nan[0].z = f64::NAN;
        nan[1].z = f64::NAN;
        assert!(!plane.carries(&nan, r));
    }

    #[test]
    fn the_table_is_fitted_to_the_depth_outside_the_rope() {
        // A plane tilted 10 degrees about x, 0.6 m away at the centre, seen
        // by a 640x480 camera of focal 615 px.
        let tilt: f64 = 10f64.to_radians();
        let mut t = Table::new(640, 480, 615.0, 0);
        for v in 0..480 {
            for u in 0..640 {
                let ray = Vec3::new((u as f64 - 320.0) / 615.0, (v as f64 - 240.0) / 615.0, 1.0);
                // Plane: n . p = d with n = (0, sin, -cos), through (0, 0, 0.6).
                let n = Vec3::new(0.0, libm::sin(tilt), -libm::cos(tilt));
                let d = n.dot(&Vec3::new(0.0, 0.0, 0.6)) / n.dot(&ray);
                t.depth[v * 640 + u] = libm::round(ray.z * d * 1000.0) as u16;
            }
        }
        let frame = t.frame();
        let p = fit_table(&t.evidence(&frame, &[], 0.0075)).expect("plane");
        assert!(p.normal.z < 0.0, "faces the camera: {:?}", p.normal);
        assert!(
            (p.normal.y.abs() - libm::sin(tilt)).abs() < 0.01,
            "{:?}",
            p.normal
        );
        assert!((p.normal.dot(&Vec3::new(0.0, 0.0, 0.6)) - p.offset).abs() < 0.002);
    }
}
