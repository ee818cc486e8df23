//! The table the rope lies on: a plane fitted to the depth image outside
//! the rope (CDCPD2's table constraint, and where a rope that came out from
//! under an occluder must lie).

use alloc::vec::Vec;

use crate::math::Vec3;
use crate::perception::evidence::Evidence;

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
