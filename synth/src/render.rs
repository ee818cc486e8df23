//! The renderer: a pinhole camera (D435i colour intrinsics) looking straight
//! down at the table, ray casting the rope as a chain of capsules, the table
//! plane and optional occluder boxes; Lambert shading, a braided texture,
//! table texture, vignetting and colour noise; and depth with the D435i's
//! behaviour (noise growing with z^2, holes and flying pixels at edges,
//! random dropouts, millimetre quantisation, 0 where invalid).

use alloc::vec;
use alloc::vec::Vec;

use upetrack::math::{self, Vec3};
use upetrack::perception::segmentation::rgb_to_hsv;
use upetrack::rng::SplitMix64;
use upetrack::{CameraIntrinsics, HsvRange};

/// Stereo baseline of the D435i, metres.
pub const D435I_BASELINE: f64 = 0.050;

/// How an image is rendered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Colour intrinsics (depth is aligned to colour).
    pub camera: CameraIntrinsics,
    /// Distance from the camera to the table's centre along the optical
    /// axis, metres (its height when looking straight down). Default 0.6.
    pub camera_height: f64,
    /// Tilt of the optical axis from straight down, radians, towards the
    /// table's -y side (the camera moves to -y and looks back at the
    /// centre). Default 0.
    pub camera_tilt: f64,
    /// Rope albedo, RGB in [0, 1]. Default a mid blue like TrackDLO's rope.
    pub rope_color: [f64; 3],
    /// Table albedo, RGB in [0, 1]. Default off-white.
    pub table_color: [f64; 3],
    /// Occluder albedo, RGB in [0, 1]. Default grey.
    pub occluder_color: [f64; 3],
    /// Pitch of the braid texture along the rope, metres. Default 8 mm.
    pub braid_pitch: f64,
    /// Standard deviation of the colour noise, 8-bit levels. Default 2.5.
    pub color_noise: f64,
    /// Subpixel disparity noise of the stereo matcher, pixels. Default 0.08.
    pub subpixel_noise: f64,
    /// Multiplier on the depth noise. Default 1.
    pub depth_noise_multiplier: f64,
    /// Probability that a pixel on a depth edge has no depth. Default 0.35.
    pub edge_hole_probability: f64,
    /// Probability that a pixel on a depth edge is a flying pixel. Default 0.15.
    pub flying_pixel_probability: f64,
    /// Probability of a random dropout anywhere. Default 0.002.
    pub dropout_probability: f64,
    /// Strength of the vignetting at the image corners, in [0, 1]. Default 0.25.
    pub vignetting: f64,
    /// Translation of the camera's centre from where height and tilt put
    /// it, world frame, metres (a camera on an arm or in a hand). Default 0.
    pub camera_shift: [f64; 3],
    /// Small rotation of the camera about its own x, y and z axes, radians,
    /// applied after the tilt. Default 0.
    pub camera_turn: [f64; 3],
    /// A second albedo for every other strand of the braid (a two-tone
    /// rope), RGB in [0, 1]; `None` for one colour. Default `None`.
    pub rope_second_color: Option<[f64; 3]>,
    /// Contrast of the table's texture about its mean, times the default
    /// grain's. Default 1.
    pub table_texture: f64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            camera: CameraIntrinsics::D435I_640X480,
            camera_height: 0.6,
            camera_tilt: 0.0,
            rope_color: [0.08, 0.22, 0.55],
            table_color: [0.86, 0.87, 0.85],
            occluder_color: [0.45, 0.42, 0.38],
            braid_pitch: 0.008,
            color_noise: 2.5,
            subpixel_noise: 0.08,
            depth_noise_multiplier: 1.0,
            edge_hole_probability: 0.35,
            flying_pixel_probability: 0.15,
            dropout_probability: 0.002,
            vignetting: 0.25,
            camera_shift: [0.0; 3],
            camera_turn: [0.0; 3],
            rope_second_color: None,
            table_texture: 1.0,
        }
    }
}

/// An axis-aligned box in the world frame (table at z = 0, z up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OccluderBox {
    /// Minimum corner, metres.
    pub min: Vec3,
    /// Maximum corner, metres.
    pub max: Vec3,
    /// Its albedo, RGB in [0, 1]; `None` for the occluders' colour of the
    /// render settings.
    pub color: Option<[f64; 3]>,
}

/// A rendered frame.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// RGB8, row-major.
    pub rgb: Vec<u8>,
    /// Depth in millimetres, 0 where invalid.
    pub depth: Vec<u16>,
}

/// Where the camera is: world-to-camera rotation (rows: the camera's x
/// right, y down, z forward in world coordinates) and its centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Rows of the rotation.
    pub rows: [Vec3; 3],
    /// Camera centre, world frame.
    pub centre: Vec3,
}

impl CameraPose {
    /// World (table frame) to camera frame.
    pub fn world_to_camera(&self, p: &Vec3) -> Vec3 {
        let d = p - self.centre;
        Vec3::new(
            self.rows[0].dot(&d),
            self.rows[1].dot(&d),
            self.rows[2].dot(&d),
        )
    }

    /// The motion of points at rest in the world from this pose's camera
    /// frame to `next`'s.
    pub fn motion_to(&self, next: &CameraPose) -> upetrack::motion::RigidMotion {
        let rows = |p: &CameraPose| nalgebra::Matrix3::from_rows(&p.rows.map(|r| r.transpose()));
        upetrack::motion::RigidMotion::between_camera_poses(
            &rows(self),
            &self.centre,
            &rows(next),
            &next.centre,
        )
    }

    /// A world-frame direction in the camera frame.
    pub fn direction_to_camera(&self, d: &Vec3) -> Vec3 {
        Vec3::new(
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        )
    }

    /// A camera-frame direction in the world frame.
    pub fn direction_to_world(&self, d: &Vec3) -> Vec3 {
        self.rows[0] * d.x + self.rows[1] * d.y + self.rows[2] * d.z
    }
}

impl RenderSettings {
    /// The camera's pose: `camera_height` from the table's centre along an
    /// axis tilted by `camera_tilt` from straight down, then turned by
    /// `camera_turn` and moved by `camera_shift`.
    pub fn pose(&self) -> CameraPose {
        let (s, c) = (libm::sin(self.camera_tilt), libm::cos(self.camera_tilt));
        let x = Vec3::new(1.0, 0.0, 0.0);
        let z = Vec3::new(0.0, s, -c);
        let mut rows = [x, z.cross(&x), z];
        if self.camera_turn != [0.0; 3] {
            rows = turned(rows, self.camera_turn);
        }
        let [dx, dy, dz] = self.camera_shift;
        CameraPose {
            rows,
            centre: Vec3::new(dx, dy - self.camera_height * s, dz + self.camera_height * c),
        }
    }

    /// World (table frame) to camera frame.
    pub fn world_to_camera(&self, p: &Vec3) -> Vec3 {
        self.pose().world_to_camera(p)
    }
}

/// The camera's axes `rows` turned by `angles` about its own x, then y,
/// then z axis (radians).
fn turned(rows: [Vec3; 3], angles: [f64; 3]) -> [Vec3; 3] {
    let [mut x, mut y, mut z] = rows;
    for (k, a) in angles.into_iter().enumerate() {
        let (s, c) = (libm::sin(a), libm::cos(a));
        // Rotating about one axis mixes the other two.
        let (p, q) = match k {
            0 => (y, z),
            1 => (z, x),
            _ => (x, y),
        };
        let (p2, q2) = (p * c + q * s, q * c - p * s);
        match k {
            0 => (y, z) = (p2, q2),
            1 => (z, x) = (p2, q2),
            _ => (x, y) = (p2, q2),
        }
    }
    [x, y, z]
}

#[derive(Clone, Copy)]
enum Surface {
    Table,
    Rope {
        s: f64,
        n: Vec3,
        axis: Vec3,
        look: usize,
    },
    Box {
        n: Vec3,
        albedo: [f64; 3],
    },
}

/// Ray (origin 0, unit direction `rd`) against the capsule `a`-`b` of radius `r`.
/// Returns the distance and the parameter along the axis in [0, 1].
fn ray_capsule(rd: &Vec3, a: &Vec3, b: &Vec3, r: f64) -> Option<(f64, f64)> {
    let ba = b - a;
    let oa = -a;
    let baba = ba.dot(&ba);
    let bard = ba.dot(rd);
    let baoa = ba.dot(&oa);
    let rdoa = rd.dot(&oa);
    let oaoa = oa.dot(&oa);
    let qa = baba - bard * bard;
    if qa > 1e-14 {
        let qb = baba * rdoa - baoa * bard;
        let qc = baba * oaoa - baoa * baoa - r * r * baba;
        let h = qb * qb - qa * qc;
        if h >= 0.0 {
            let t = (-qb - math::sqrt(h)) / qa;
            let y = baoa + t * bard;
            if y > 0.0 && y < baba && t > 0.0 {
                return Some((t, y / baba));
            }
        }
    }
    // End caps (spheres at a and b).
    let mut best: Option<(f64, f64)> = None;
    for (c, param) in [(a, 0.0), (b, 1.0)] {
        let oc = -c;
        let qb = rd.dot(&oc);
        let qc = oc.dot(&oc) - r * r;
        let h = qb * qb - qc;
        if h > 0.0 {
            let t = -qb - math::sqrt(h);
            if t > 0.0 && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, param));
            }
        }
    }
    best
}

/// Ray against an axis-aligned box (camera frame); distance and normal.
fn ray_box(rd: &Vec3, min: &Vec3, max: &Vec3) -> Option<(f64, Vec3)> {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    let mut normal = Vec3::zeros();
    for k in 0..3 {
        if rd[k].abs() < 1e-15 {
            if 0.0 < min[k] || 0.0 > max[k] {
                return None;
            }
            continue;
        }
        let (mut a, mut b) = (min[k] / rd[k], max[k] / rd[k]);
        let mut sign = -1.0;
        if a > b {
            core::mem::swap(&mut a, &mut b);
            sign = 1.0;
        }
        if a > t0 {
            t0 = a;
            normal = Vec3::zeros();
            normal[k] = sign;
        }
        t1 = t1.min(b);
    }
    (t0 <= t1 && t0 > 0.0).then_some((t0, normal))
}

/// `true` when something `hits` (given the ray from the camera, relative
/// to its centre, and the origin it is taken from) is hit along the line
/// of sight to the near side of the rope at `point` (world frame, radius
/// `radius`) before it: `hits(dir, centre, before)`.
fn hidden_by(
    settings: &RenderSettings,
    point: &Vec3,
    radius: f64,
    hits: impl Fn(&Vec3, &Vec3, f64) -> bool,
) -> bool {
    let pose = settings.pose();
    let to = point - pose.centre;
    let dist = math::norm(&to);
    dist > radius && hits(&(to / dist), &pose.centre, dist - radius)
}

/// `true` when a box lies between the camera and the near side of the rope
/// at `point` (world frame, rope radius `radius`).
pub fn hidden_by_boxes(
    settings: &RenderSettings,
    point: &Vec3,
    radius: f64,
    boxes: &[OccluderBox],
) -> bool {
    hidden_by(settings, point, radius, |dir, centre, before| {
        boxes.iter().any(|b| {
            ray_box(dir, &(b.min - centre), &(b.max - centre)).is_some_and(|(t, _)| t < before)
        })
    })
}

/// `true` when another rope (`others`, world frame) lies between the
/// camera and the near side of the rope at `point` (world frame, radius
/// `radius`): the near side's centre, so a rope merely grazed at its edge
/// still counts as seen.
pub fn hidden_by_ropes(
    settings: &RenderSettings,
    point: &Vec3,
    radius: f64,
    others: &[RopeLook<'_>],
) -> bool {
    hidden_by(settings, point, radius, |dir, centre, before| {
        others.iter().any(|o| {
            o.particles.windows(2).any(|s| {
                ray_capsule(dir, &(s[0] - centre), &(s[1] - centre), o.radius)
                    .is_some_and(|(t, _)| t < before)
            })
        })
    })
}

/// Smooth value noise in [0, 1] on a lattice of `cell` metres (table texture).
fn value_noise(x: f64, y: f64, cell: f64, seed: u64) -> f64 {
    let hash = |i: i64, j: i64| {
        let mut r = SplitMix64::new(
            seed ^ (i as u64).wrapping_mul(0x9E37_79B9) ^ (j as u64).wrapping_mul(0x85EB_CA6B),
        );
        r.uniform()
    };
    let (fx, fy) = (x / cell, y / cell);
    let (ix, iy) = (math::floor(fx), math::floor(fy));
    let (tx, ty) = (fx - ix, fy - iy);
    let (sx, sy) = (tx * tx * (3.0 - 2.0 * tx), ty * ty * (3.0 - 2.0 * ty));
    let (i, j) = (ix as i64, iy as i64);
    let a = hash(i, j) + (hash(i + 1, j) - hash(i, j)) * sx;
    let b = hash(i, j + 1) + (hash(i + 1, j + 1) - hash(i, j + 1)) * sx;
    a + (b - a) * sy
}

/// One rope as the renderer draws it.
#[derive(Debug, Clone, Copy)]
pub struct RopeLook<'a> {
    /// Particles, world frame, metres.
    pub particles: &'a [Vec3],
    /// Radius, metres.
    pub radius: f64,
    /// Albedo, RGB in [0, 1].
    pub color: [f64; 3],
    /// A second albedo for every other strand (a two-tone rope).
    pub second_color: Option<[f64; 3]>,
}

/// Renders the rope (particles in the world frame, radius `r`, in the
/// settings' colours) and boxes.
pub fn render(
    settings: &RenderSettings,
    particles: &[Vec3],
    radius: f64,
    boxes: &[OccluderBox],
    rng: &mut SplitMix64,
) -> Rendered {
    let look = RopeLook {
        particles,
        radius,
        color: settings.rope_color,
        second_color: settings.rope_second_color,
    };
    render_ropes(settings, &[look], boxes, rng)
}

/// Renders several ropes and boxes (the settings' rope colours unused).
pub fn render_ropes(
    settings: &RenderSettings,
    ropes: &[RopeLook<'_>],
    boxes: &[OccluderBox],
    rng: &mut SplitMix64,
) -> Rendered {
    let cam = &settings.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let pose = settings.pose();
    let ray = |u: usize, v: usize| {
        let d = Vec3::new(
            (u as f64 - cam.cx) / cam.fx,
            (v as f64 - cam.cy) / cam.fy,
            1.0,
        );
        d / math::norm(&d)
    };
    // Start with the table (world z = 0) everywhere it is in view; above
    // the horizon of a tilted camera nothing is hit (no depth, black).
    let mut dist = vec![f64::INFINITY; w * h];
    let mut surf = vec![Surface::Table; w * h];
    for v in 0..h {
        for u in 0..w {
            let down = pose.direction_to_world(&ray(u, v)).z;
            if down < 0.0 {
                dist[v * w + u] = -pose.centre.z / down;
            }
        }
    }
    let bbox = |ps: &[Vec3], margin: f64| -> Option<(usize, usize, usize, usize)> {
        let (mut u0, mut v0, mut u1, mut v1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in ps {
            let q = cam.project(p)?;
            u0 = u0.min(q.x);
            v0 = v0.min(q.y);
            u1 = u1.max(q.x);
            v1 = v1.max(q.y);
        }
        let clampu = |x: f64| x.clamp(0.0, (w - 1) as f64) as usize;
        let clampv = |x: f64| x.clamp(0.0, (h - 1) as f64) as usize;
        if u1 + margin < 0.0
            || v1 + margin < 0.0
            || u0 - margin > w as f64
            || v0 - margin > h as f64
        {
            return None;
        }
        Some((
            clampu(u0 - margin),
            clampu(u1 + margin) + 1,
            clampv(v0 - margin),
            clampv(v1 + margin) + 1,
        ))
    };
    for (look, rope) in ropes.iter().enumerate() {
        let radius = rope.radius;
        let pts: Vec<Vec3> = rope
            .particles
            .iter()
            .map(|p| pose.world_to_camera(p))
            .collect();
        let mut arc = vec![0.0; pts.len()];
        for i in 1..pts.len() {
            arc[i] = arc[i - 1] + math::norm(&(pts[i] - pts[i - 1]));
        }
        for i in 0..pts.len().saturating_sub(1) {
            let (a, b) = (pts[i], pts[i + 1]);
            let zmin = a.z.min(b.z) - radius;
            if zmin <= 1e-3 {
                continue;
            }
            let margin = radius * cam.fx.max(cam.fy) / zmin + 2.0;
            let Some((u0, u1, v0, v1)) = bbox(&[a, b], margin) else {
                continue;
            };
            let axis = (b - a) / math::norm(&(b - a)).max(1e-12);
            for v in v0..v1.min(h) {
                for u in u0..u1.min(w) {
                    let rd = ray(u, v);
                    if let Some((t, param)) = ray_capsule(&rd, &a, &b, radius) {
                        let k = v * w + u;
                        if t < dist[k] {
                            let p = rd * t;
                            let c = a + (b - a) * param;
                            let n = (p - c) / math::norm(&(p - c)).max(1e-12);
                            dist[k] = t;
                            surf[k] = Surface::Rope {
                                s: arc[i] + param * (arc[i + 1] - arc[i]),
                                n,
                                axis,
                                look,
                            };
                        }
                    }
                }
            }
        }
    }
    for bx in boxes {
        let corners: Vec<Vec3> = (0..8)
            .map(|c| {
                let p = Vec3::new(
                    if c & 1 == 0 { bx.min.x } else { bx.max.x },
                    if c & 2 == 0 { bx.min.y } else { bx.max.y },
                    if c & 4 == 0 { bx.min.z } else { bx.max.z },
                );
                pose.world_to_camera(&p)
            })
            .collect();
        if corners.iter().any(|p| p.z <= 1e-3) {
            continue;
        }
        let Some((u0, u1, v0, v1)) = bbox(&corners, 2.0) else {
            continue;
        };
        // The box is axis-aligned in the world: intersect there, from the
        // camera centre, and turn the normal into the camera frame.
        let (mn, mx) = (bx.min - pose.centre, bx.max - pose.centre);
        for v in v0..v1.min(h) {
            for u in u0..u1.min(w) {
                let rd = ray(u, v);
                if let Some((t, n)) = ray_box(&pose.direction_to_world(&rd), &mn, &mx) {
                    let n = pose.direction_to_camera(&n);
                    let k = v * w + u;
                    if t < dist[k] {
                        dist[k] = t;
                        surf[k] = Surface::Box {
                            n,
                            albedo: bx.color.unwrap_or(settings.occluder_color),
                        };
                    }
                }
            }
        }
    }

    // Shading.
    let light = Vec3::new(-0.3, -0.4, -1.0).normalize(); // towards the light, camera frame
    let (ambient, diffuse) = (0.35, 0.75);
    let tex_seed = 0x7AB1E;
    let diag = math::sqrt(cam.cx * cam.cx + cam.cy * cam.cy).max(1.0);
    let mut rgb = vec![0u8; w * h * 3];
    let mut depth_m = vec![0.0f64; w * h];
    for v in 0..h {
        for u in 0..w {
            let k = v * w + u;
            let rd = ray(u, v);
            if !dist[k].is_finite() {
                // Nothing in view (above a tilted camera's horizon).
                depth_m[k] = f64::INFINITY;
                continue;
            }
            let p = rd * dist[k];
            depth_m[k] = p.z;
            let (albedo, lambert, texture) = match surf[k] {
                Surface::Table => {
                    let world = pose.centre + pose.direction_to_world(&p);
                    let (world_x, world_y) = (world.x, world.y);
                    let mut t = 0.94
                        + 0.06 * value_noise(world_x, world_y, 0.01, tex_seed)
                        + 0.03 * (value_noise(world_x, world_y, 0.002, tex_seed + 1) - 0.5);
                    if settings.table_texture != 1.0 {
                        // About the grain's mean, 0.97.
                        t = 0.97 + (t - 0.97) * settings.table_texture;
                    }
                    (
                        settings.table_color,
                        light
                            .dot(&pose.direction_to_camera(&Vec3::new(0.0, 0.0, 1.0)))
                            .max(0.0),
                        t,
                    )
                }
                Surface::Rope { s, n, axis, look } => {
                    let rope = &ropes[look];
                    // Helical strands: phase along the rope plus angle around it.
                    let e1 = axis.cross(&Vec3::new(0.0, 0.0, 1.0));
                    let e1 = if e1.norm() > 1e-9 {
                        e1.normalize()
                    } else {
                        Vec3::new(1.0, 0.0, 0.0)
                    };
                    let e2 = axis.cross(&e1);
                    let theta = libm::atan2(n.dot(&e2), n.dot(&e1));
                    let phase = core::f64::consts::TAU * s / settings.braid_pitch + 2.0 * theta;
                    let wave = libm::cos(phase);
                    let albedo = match rope.second_color {
                        Some(second) if wave < 0.0 => second,
                        _ => rope.color,
                    };
                    (albedo, n.dot(&light).max(0.0), 0.78 + 0.22 * wave)
                }
                Surface::Box { n, albedo } => (albedo, n.dot(&light).abs(), 1.0),
            };
            let lambert = lambert.min(1.0);
            let r2 = ((u as f64 - cam.cx) * (u as f64 - cam.cx)
                + (v as f64 - cam.cy) * (v as f64 - cam.cy))
                / (diag * diag);
            let vignette = 1.0 - settings.vignetting * r2;
            for c in 0..3 {
                let value = albedo[c] * (ambient + diffuse * lambert) * texture * vignette * 255.0
                    + settings.color_noise * rng.normal();
                rgb[3 * k + c] = libm::round(value).clamp(0.0, 255.0) as u8;
            }
        }
    }

    // Depth: D435i-like noise, edges, dropouts, millimetres.
    let focal = 0.5 * (cam.fx + cam.fy);
    let mut depth = vec![0u16; w * h];
    const EDGE_STEP: f64 = 0.008;
    for v in 0..h {
        for u in 0..w {
            let k = v * w + u;
            let z = depth_m[k];
            if !z.is_finite() {
                continue;
            }
            let mut edge_other = None;
            for (du, dv) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (nu, nv) = (u as i64 + du, v as i64 + dv);
                if nu >= 0 && nv >= 0 && (nu as usize) < w && (nv as usize) < h {
                    let zn = depth_m[nv as usize * w + nu as usize];
                    if (zn - z).abs() > EDGE_STEP {
                        edge_other = Some(zn);
                    }
                }
            }
            let roll = rng.uniform();
            let mut z_out = z;
            if let Some(zn) = edge_other {
                if roll < settings.edge_hole_probability {
                    continue;
                }
                if roll < settings.edge_hole_probability + settings.flying_pixel_probability {
                    z_out = z + (zn - z) * rng.uniform();
                }
            } else if roll < settings.dropout_probability {
                continue;
            }
            let sigma = z_out * z_out * settings.subpixel_noise / (focal * D435I_BASELINE)
                * settings.depth_noise_multiplier;
            let mm = libm::round((z_out + sigma * rng.normal()) * 1000.0);
            if mm >= 1.0 && mm <= u16::MAX as f64 {
                depth[k] = mm as u16;
            }
        }
    }
    Rendered { rgb, depth }
}

/// HSV thresholds that fit a rope of albedo `color` (RGB in [0, 1]) in
/// OpenCV's convention: its hue +-15, saturation from 60 % of its own, any
/// value above 20; for a black, grey or white rope, the range clicking it
/// picks ([`HsvRange::around`]).
pub fn rope_hsv(color: [f64; 3]) -> HsvRange {
    let rgb = albedo_rgb8(color);
    let [h, s, v] = rgb_to_hsv(rgb);
    if HsvRange::is_achromatic([h, s, v]) {
        // Black, grey or white: the range a user picks by clicking it.
        return HsvRange::around(rgb);
    }
    let lo = (h as i32 - 15).rem_euclid(180) as u8;
    let hi = (h as i32 + 15).rem_euclid(180) as u8;
    HsvRange::new([lo, (s as f64 * 0.6) as u8, 20], [hi, 255, 255])
}

/// An albedo (RGB in [0, 1]) as the 8-bit colour a pixel lit at full
/// strength shows.
pub(crate) fn albedo_rgb8(color: [f64; 3]) -> [u8; 3] {
    color.map(|x| libm::round(x * 255.0).clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_capsule_body_and_caps() {
        let a = Vec3::new(-0.1, 0.0, 0.5);
        let b = Vec3::new(0.1, 0.0, 0.5);
        let (t, param) = ray_capsule(&Vec3::new(0.0, 0.0, 1.0), &a, &b, 0.01).expect("hit");
        assert!((t - 0.49).abs() < 1e-12 && (param - 0.5).abs() < 1e-12);
        let dir = Vec3::new(0.1, 0.0, 0.5).normalize();
        assert!(ray_capsule(&dir, &a, &b, 0.01).is_some());
        assert!(ray_capsule(&Vec3::new(0.0, 1.0, 1.0).normalize(), &a, &b, 0.01).is_none());
    }

    #[test]
    fn depth_noise_follows_the_d435i_model() {
        // Flat table at 0.6 m: the spread of depth is z^2 * 0.08 / (615 * 0.05) = 0.94 mm
        // (plus millimetre quantisation, variance 1/12 mm^2).
        let mut s = RenderSettings::default();
        s.camera.width = 64;
        s.camera.height = 48;
        s.camera.cx = 32.0;
        s.camera.cy = 24.0;
        let mut rng = SplitMix64::new(1);
        let r = render(&s, &[], 0.0075, &[], &mut rng);
        let vals: Vec<f64> = r
            .depth
            .iter()
            .filter(|&&d| d > 0)
            .map(|&d| d as f64)
            .collect();
        assert!(vals.len() > 3000);
        // Remove the slant: off-centre pixels see the table farther only along the ray, z is constant.
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd = math::sqrt(
            vals.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / vals.len() as f64,
        );
        let expected = math::sqrt(
            0.6f64.powi(4) * 0.08f64.powi(2) / (615.0f64 * 0.05).powi(2) * 1e6 + 1.0 / 12.0,
        );
        assert!((mean - 600.0).abs() < 0.2, "mean {mean}");
        assert!((sd - expected).abs() < 0.15, "sd {sd} vs {expected}");
    }

    #[test]
    fn a_turned_camera_keeps_orthonormal_axes_and_no_turn_is_the_plain_pose() {
        let plain = RenderSettings {
            camera_tilt: 0.3,
            ..RenderSettings::default()
        };
        let turned = RenderSettings {
            camera_turn: [0.05, -0.03, 0.2],
            camera_shift: [0.01, 0.02, -0.03],
            ..plain
        };
        let (a, b) = (plain.pose(), turned.pose());
        for i in 0..3 {
            for j in 0..3 {
                let dot = b.rows[i].dot(&b.rows[j]);
                assert!((dot - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        // A right-handed frame still: x cross y is z.
        assert!((b.rows[0].cross(&b.rows[1]) - b.rows[2]).norm() < 1e-12);
        assert!((b.centre - a.centre - Vec3::new(0.01, 0.02, -0.03)).norm() < 1e-12);
        // About z alone the optical axis stays; x turns by the angle.
        let roll = RenderSettings {
            camera_turn: [0.0, 0.0, 0.2],
            ..plain
        }
        .pose();
        assert!((roll.rows[2] - a.rows[2]).norm() < 1e-12);
        assert!((roll.rows[0].dot(&a.rows[0]) - libm::cos(0.2)).abs() < 1e-12);
    }
}
