//! Several ropes in one frame: which rope each segmented pixel belongs to.
//!
//! The ropes compete for pixels as the components of one mixture over all
//! their nodes would, in its hard limit: a pixel goes to the tracked rope
//! whose surface passes nearest the pixel's point in 3D (so depth tells
//! the rope lying over a crossing from the one under it), if that is
//! within reach of it, and is of use to that rope if its colour range
//! accepts it (a rope's pixel that its own range misses is not another
//! rope's for that). What no tracked rope is near is left to every rope
//! whose colour it has: a rope not yet found is initialised from it, a
//! tracked one treats it as it treats clutter.

use alloc::vec;
use alloc::vec::Vec;

use super::camera::CameraIntrinsics;
use super::frame::Frame;
use super::initialisation::TakenRope;
use super::segmentation::Mask;
use crate::math::{Vec2, Vec3};
use crate::polyline::distance_to_polyline;

/// Most ropes whose pixels are shared (one bit each per pixel).
pub const MAX_SHARED: usize = 8;

/// A tracked rope as the sharing sees it.
#[derive(Debug, Clone, Copy)]
pub struct RopeLine<'a> {
    /// Its nodes, camera frame, metres.
    pub nodes: &'a [Vec3],
    /// Its radius, metres.
    pub radius: f64,
}

/// One rope's part of a frame's pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelShare {
    /// The pixels this rope may use: of its colour, and not another
    /// tracked rope's.
    pub own: Mask,
    /// The pixels of the other ropes: they hide this one where they lie.
    pub others: Mask,
    /// Another rope's colour range passes a pixel this rope's passes.
    pub alike: bool,
}

/// What the other ropes tracked in the same frame leave a rope.
#[derive(Debug, Clone)]
pub struct OtherRopes {
    /// Their pixels: they hide this rope as an occluder does.
    pub pixels: Mask,
    /// Every pixel of this rope's colour, theirs included: initialisation
    /// looks for this rope among all the candidates of its colour (so a
    /// crossing with another rope is walked straight through)...
    pub colour: Mask,
    /// ...and leaves the candidates lying along these ropes to them.
    pub taken: Vec<TakenRope>,
    /// Another rope's colour range passes pixels this rope's passes, in
    /// this frame: two ropes alike may meet end to end, so the
    /// initialisation joins no piece ends that meet only at a corner
    /// ([`super::initialisation::InitGuide::alike_ropes`]).
    pub alike: bool,
}

/// Who a pixel of some rope's colour belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    /// Rope `k`'s alone (of use to it if its colour accepts the pixel).
    Rope(usize),
    /// Every rope whose colour it has.
    Shared,
}

/// Shares the pixels of one frame between ropes: `masks[k]` is rope `k`'s
/// colour mask, `lines[k]` its tracked state (`None` while not tracked)
/// and `reach` (metres) how far from a tracked rope's surface a pixel's
/// point may lie and still be that rope's. All masks must have the
/// frame's size (a mask of another size is taken as empty, as is any
/// past the [`MAX_SHARED`]th).
pub fn share_pixels(
    frame: &Frame<'_>,
    camera: &CameraIntrinsics,
    masks: &[&Mask],
    lines: &[Option<RopeLine<'_>>],
    reach: f64,
) -> Vec<PixelShare> {
    let (w, h) = (frame.width, frame.height);
    let n = w as usize * h as usize;
    let usable: Vec<bool> = masks
        .iter()
        .enumerate()
        .map(|(k, m)| k < MAX_SHARED && m.data.len() == n)
        .collect();
    let windows: Vec<Option<Window>> = (0..masks.len())
        .map(|k| {
            let line = lines.get(k).copied().flatten()?;
            Window::of(&line, camera, reach)
        })
        .collect();
    let axes: Vec<Option<Axis>> = (0..masks.len())
        .map(|k| lines.get(k).copied().flatten().map(|l| Axis::of(&l)))
        .collect();
    // Each rope's segment nearest the last pixel looked at.
    let mut starts = vec![0usize; masks.len()];
    // Which ropes' colours each pixel has, one bit per rope.
    let mut colours = vec![0u8; n];
    for (k, mask) in masks.iter().enumerate().filter(|(k, _)| usable[*k]) {
        for (c, &on) in colours.iter_mut().zip(&mask.data) {
            *c |= u8::from(on) << k;
        }
    }
    let mut shares: Vec<PixelShare> = masks
        .iter()
        .map(|_| PixelShare {
            own: Mask::new(w, h),
            others: Mask::new(w, h),
            alike: false,
        })
        .collect();
    for (i, &bits) in colours.iter().enumerate().filter(|(_, b)| **b != 0) {
        let (u, v) = ((i % w as usize) as f64, (i / w as usize) as f64);
        let owner = owner_of(
            bits,
            u,
            v,
            frame.depth[i],
            frame,
            camera,
            (lines, &axes, &mut starts),
            &windows,
            reach,
        );
        for (k, share) in shares.iter_mut().enumerate() {
            let of_colour = bits & (1 << k) != 0;
            share.alike |= of_colour && bits & !(1 << k) != 0;
            match owner {
                // The nearest rope's, if it has its colour (else nobody's).
                Owner::Rope(j) if j == k => share.own.data[i] = of_colour,
                Owner::Rope(_) => share.others.data[i] = true,
                Owner::Shared => share.own.data[i] = of_colour,
            }
        }
    }
    shares
}

/// The owner of a pixel `(u, v)` (raw depth `raw`) that the colours of the
/// ropes in `bits` accept: the tracked rope whose surface is nearest its
/// point, of whatever colour (a rope's pixel that its own colour range
/// misses is still not another rope's), if within reach; else the one
/// rope of its colour, or every one.
#[allow(clippy::too_many_arguments)]
fn owner_of(
    bits: u8,
    u: f64,
    v: f64,
    raw: u16,
    frame: &Frame<'_>,
    camera: &CameraIntrinsics,
    (lines, axes, starts): (&[Option<RopeLine<'_>>], &[Option<Axis>], &mut [usize]),
    windows: &[Option<Window>],
    reach: f64,
) -> Owner {
    let by_colour = if bits.is_power_of_two() {
        Owner::Rope(bits.trailing_zeros() as usize)
    } else {
        Owner::Shared
    };
    let near = |k: &usize| windows[*k].as_ref().is_some_and(|win| win.contains(u, v));
    let mut tracked = (0..windows.len()).filter(near);
    match (tracked.next(), tracked.next()) {
        // Within reach of no tracked rope.
        (None, _) => return by_colour,
        // Near one tracked rope only, of its colour: no other wants it.
        (Some(k), None) if bits & (1 << k) != 0 => return Owner::Rope(k),
        _ => {}
    }
    let point = (raw != 0).then(|| camera.deproject(u, v, raw as f64 * frame.depth_scale));
    let nearest = (0..windows.len())
        .filter(near)
        .filter_map(|k| {
            let line = lines.get(k).copied().flatten()?;
            let d = match (point, windows[k].as_ref()) {
                (Some(p), _) => axes[k].as_ref()?.surface_distance_from(&p, &mut starts[k]),
                (None, Some(win)) => win.distance_in_image(Vec2::new(u, v), line.radius),
                (None, None) => return None,
            };
            Some((k, d))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match nearest {
        Some((k, d)) if d <= reach => Owner::Rope(k),
        _ => by_colour,
    }
}

/// Distance from `p` to the surface of `line` (its axis less its radius),
/// metres; infinite for a line without nodes.
#[cfg(test)]
fn surface_distance(p: &Vec3, line: &RopeLine<'_>) -> f64 {
    Axis::of(line).surface_distance_from(p, &mut 0)
}

/// Squared distance from `p` to the segment from `a` along `ab`.
#[inline]
fn nearest_squared(p: &Vec3, a: &Vec3, ab: &Vec3) -> f64 {
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm_squared()
}

/// A tracked rope's axis, its segments measured once for every pixel.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    /// Each segment's start, direction (end less start), middle and half
    /// length.
    segments: Vec<(Vec3, Vec3, Vec3, f64)>,
    /// A rope of one node: where it is.
    single: Option<Vec3>,
    radius: f64,
}

impl Axis {
    pub(crate) fn of(line: &RopeLine<'_>) -> Self {
        Self {
            segments: line
                .nodes
                .windows(2)
                .map(|s| {
                    (
                        s[0],
                        s[1] - s[0],
                        (s[0] + s[1]) * 0.5,
                        0.5 * (s[1] - s[0]).norm(),
                    )
                })
                .collect(),
            single: match line.nodes {
                [only] => Some(*only),
                _ => None,
            },
            radius: line.radius,
        }
    }

    /// `true` when a point of the axis lies within `reach` of `p`
    /// (metres; the radius not taken off), looking first at segment
    /// `*start` and leaving there the segment that was within reach: a
    /// yes costs one segment most often, not the nearest's search.
    pub(crate) fn axis_within(&self, p: &Vec3, reach: f64, start: &mut usize) -> bool {
        if let Some(only) = self.single {
            return (p - only).norm_squared() <= reach * reach;
        }
        let n = self.segments.len();
        for j in (0..n).map(|j| (j + *start) % n) {
            let (a, ab, mid, half) = &self.segments[j];
            let bound = reach + half;
            if (p - mid).norm_squared() > bound * bound {
                continue;
            }
            if nearest_squared(p, a, ab) <= reach * reach {
                *start = j;
                return true;
            }
        }
        false
    }

    /// Distance from `p` to the rope's surface (its axis less its
    /// radius), metres, infinite for a rope without nodes; looking first
    /// at segment `*start` (the nearest to the last pixel, most often the
    /// nearest to this one) and leaving the nearest there.
    fn surface_distance_from(&self, p: &Vec3, start: &mut usize) -> f64 {
        if let Some(only) = self.single {
            return (p - only).norm() - self.radius;
        }
        let n = self.segments.len();
        let (mut best, mut best2, mut nearest) = (f64::INFINITY, f64::INFINITY, *start);
        for j in (0..n).map(|j| (j + *start) % n) {
            let (a, ab, mid, half) = &self.segments[j];
            // No point of a segment is nearer than its middle less half its
            // length: most segments are passed over at that.
            let reach = best + half;
            if (p - mid).norm_squared() > reach * reach {
                continue;
            }
            let d2 = nearest_squared(p, a, ab);
            if d2 < best2 {
                (best2, best, nearest) = (d2, libm::sqrt(d2), j);
            }
        }
        *start = nearest;
        best - self.radius
    }
}

/// The pixels within reach of a tracked rope: its projected nodes' box,
/// widened by the reach at its nearest node.
#[derive(Debug, Clone)]
struct Window {
    min: Vec2,
    max: Vec2,
    /// Each projected segment's box, widened as the whole: a long rope's
    /// box holds much that is far from it.
    pieces: Vec<(Vec2, Vec2)>,
    /// Metres per pixel at the rope's nearest node.
    metres_per_px: f64,
    /// The rope's nodes projected into the image.
    projected: Vec<Vec2>,
}

impl Window {
    fn of(line: &RopeLine<'_>, camera: &CameraIntrinsics, reach: f64) -> Option<Self> {
        let nearest = line
            .nodes
            .iter()
            .map(|p| p.z)
            .filter(|z| *z > 0.0)
            .fold(f64::INFINITY, f64::min);
        if !nearest.is_finite() {
            return None;
        }
        let focal = camera.fx.max(camera.fy);
        let margin = Vec2::repeat((reach + line.radius) * focal / nearest + 1.0);
        let projected: Vec<Vec2> = line
            .nodes
            .iter()
            .filter_map(|p| camera.project(p))
            .collect();
        let pieces: Vec<(Vec2, Vec2)> = match projected.as_slice() {
            [only] => alloc::vec![(only - margin, only + margin)],
            many => many
                .windows(2)
                .map(|s| (s[0].inf(&s[1]) - margin, s[0].sup(&s[1]) + margin))
                .collect(),
        };
        let min = pieces
            .iter()
            .fold(Vec2::repeat(f64::INFINITY), |m, p| m.inf(&p.0));
        let max = pieces
            .iter()
            .fold(Vec2::repeat(f64::NEG_INFINITY), |m, p| m.sup(&p.1));
        (min.x <= max.x).then(|| Self {
            min,
            max,
            pieces,
            metres_per_px: nearest / focal,
            projected,
        })
    }

    fn contains(&self, u: f64, v: f64) -> bool {
        let within = |(lo, hi): &(Vec2, Vec2)| u >= lo.x && u <= hi.x && v >= lo.y && v <= hi.y;
        within(&(self.min, self.max)) && self.pieces.iter().any(within)
    }

    /// For a pixel without depth: its distance in the image to the rope's
    /// projected surface, in metres at the rope's nearest node.
    fn distance_in_image(&self, q: Vec2, radius: f64) -> f64 {
        distance_to_polyline(&q, &self.projected)
            .map_or(f64::INFINITY, |px| px * self.metres_per_px - radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::camera::CameraIntrinsics;

    const W: u32 = 160;
    const H: u32 = 120;

    fn camera() -> CameraIntrinsics {
        CameraIntrinsics {
            width: W,
            height: H,
            fx: 200.0,
            fy: 200.0,
            cx: 80.0,
            cy: 60.0,
        }
    }

    /// A frame over a table 0.6 m away, with `ropes` (each a polyline of
    /// radius `r`) drawn into one mask and the depth of their surfaces.
    struct Scene {
        rgb: Vec<u8>,
        depth: Vec<u16>,
        mask: Mask,
    }

    impl Scene {
        fn new(ropes: &[(&[Vec3], f64)]) -> Self {
            let cam = camera();
            let n = (W * H) as usize;
            let mut depth = vec![600u16; n];
            let mut mask = Mask::new(W, H);
            for v in 0..H {
                for u in 0..W {
                    // The nearest rope surface on this pixel's ray, sampled.
                    let ray = cam.deproject(u as f64, v as f64, 1.0);
                    let mut best = f64::INFINITY;
                    for (line, r) in ropes {
                        for step in 0..2000 {
                            let z = 0.45 + step as f64 * 0.0001;
                            let p = ray * z;
                            let l = RopeLine {
                                nodes: line,
                                radius: *r,
                            };
                            if surface_distance(&p, &l) <= 0.0 {
                                best = best.min(z);
                                break;
                            }
                        }
                    }
                    if best.is_finite() {
                        let i = (v * W + u) as usize;
                        depth[i] = (best * 1000.0).round() as u16;
                        mask.data[i] = true;
                    }
                }
            }
            Self {
                rgb: vec![0; n * 3],
                depth,
                mask,
            }
        }

        fn frame(&self) -> Frame<'_> {
            Frame::new(W, H, &self.rgb, &self.depth, 0.001).expect("frame")
        }
    }

    /// A straight rope of 12 nodes along x from -0.1 to 0.1 m, at `y` and
    /// depth `z`.
    fn along_x(y: f64, z: f64) -> Vec<Vec3> {
        segment(Vec3::new(-0.1, y, z), Vec3::new(0.1, y, z), 12)
    }

    /// A tracked rope of radius `r` through `nodes`.
    fn tracked(nodes: &[Vec3], r: f64) -> Option<RopeLine<'_>> {
        Some(RopeLine { nodes, radius: r })
    }

    fn segment(a: Vec3, b: Vec3, count: usize) -> Vec<Vec3> {
        (0..count)
            .map(|i| a + (b - a) * (i as f64 / (count - 1) as f64))
            .collect()
    }

    /// Pixels of `share.own` whose point lies nearer `line`'s axis than
    /// `other`'s: the share is right when every own pixel does.
    fn misassigned(scene: &Scene, share: &Mask, line: &[Vec3], other: &[Vec3]) -> usize {
        let cam = camera();
        let axis = |p: &Vec3, l: &[Vec3]| {
            surface_distance(
                p,
                &RopeLine {
                    nodes: l,
                    radius: 0.0,
                },
            )
        };
        (0..share.data.len())
            .filter(|&i| share.data[i])
            .filter(|&i| {
                let (u, v) = ((i % W as usize) as f64, (i / W as usize) as f64);
                let p = cam.deproject(u, v, scene.depth[i] as f64 * 0.001);
                axis(&p, other) < axis(&p, line)
            })
            .count()
    }

    #[test]
    fn two_parallel_ropes_a_centimetre_apart_each_keep_their_own_pixels() {
        let r = 0.003;
        let a = along_x(-0.005, 0.597);
        let b = along_x(0.005, 0.597);
        let scene = Scene::new(&[(&a, r), (&b, r)]);
        let frame = scene.frame();
        let lines = [tracked(&a, r), tracked(&b, r)];
        let shares = share_pixels(&frame, &camera(), &[&scene.mask, &scene.mask], &lines, 0.04);
        let total = scene.mask.count();
        let (na, nb) = (shares[0].own.count(), shares[1].own.count());
        assert_eq!(na + nb, total, "every pixel goes to one rope");
        assert!(na.abs_diff(nb) * 10 < total, "{na} against {nb}");
        assert_eq!(misassigned(&scene, &shares[0].own, &a, &b), 0);
        assert_eq!(misassigned(&scene, &shares[1].own, &b, &a), 0);
        assert_eq!(shares[0].others, shares[1].own);
    }

    #[test]
    fn at_a_crossing_the_pixels_go_to_the_rope_on_top() {
        let r = 0.004;
        // `top` crosses over `under`, a diameter nearer the camera.
        let under = along_x(0.0, 0.596);
        let top = segment(Vec3::new(0.0, -0.1, 0.588), Vec3::new(0.0, 0.1, 0.588), 12);
        let scene = Scene::new(&[(&under, r), (&top, r)]);
        let frame = scene.frame();
        let lines = [tracked(&under, r), tracked(&top, r)];
        let shares = share_pixels(&frame, &camera(), &[&scene.mask, &scene.mask], &lines, 0.04);
        let cam = camera();
        let centre = cam.project(&Vec3::new(0.0, 0.0, 0.588)).expect("in view");
        let (u, v) = (centre.x.round() as i64, centre.y.round() as i64);
        assert!(shares[1].own.get(u, v), "the crossing is the top rope's");
        assert!(!shares[0].own.get(u, v) && shares[0].others.get(u, v));
        assert_eq!(misassigned(&scene, &shares[1].own, &top, &under), 0);
        // The rope underneath keeps its pixels on both sides of the crossing.
        let left = cam.project(&under[2]).expect("in view");
        let right = cam.project(&under[9]).expect("in view");
        assert!(shares[0]
            .own
            .get(left.x.round() as i64, left.y.round() as i64));
        assert!(shares[0]
            .own
            .get(right.x.round() as i64, right.y.round() as i64));
    }

    #[test]
    fn pixels_far_from_every_tracked_rope_are_left_to_all_of_its_colour() {
        let r = 0.003;
        let a = along_x(-0.05, 0.597);
        let b = along_x(0.05, 0.597);
        let scene = Scene::new(&[(&a, r), (&b, r)]);
        let frame = scene.frame();
        // Only `a` is tracked: `b`'s pixels are free for the second rope,
        // and for `a` too (as clutter), but `a`'s are `a`'s alone.
        let lines = [tracked(&a, r), None];
        let shares = share_pixels(&frame, &camera(), &[&scene.mask, &scene.mask], &lines, 0.04);
        let at = |p: &Vec3| {
            let q = camera().project(p).expect("in view");
            (q.x.round() as i64, q.y.round() as i64)
        };
        let (au, av) = at(&a[6]);
        let (bu, bv) = at(&b[6]);
        assert!(shares[0].own.get(au, av) && !shares[1].own.get(au, av));
        assert!(shares[1].others.get(au, av));
        assert!(shares[1].own.get(bu, bv) && shares[0].own.get(bu, bv));
        assert!(!shares[0].others.get(bu, bv));
    }

    /// Pixels set in `a` and not in `b`.
    fn outside(a: &Mask, b: &Mask) -> usize {
        a.data
            .iter()
            .zip(&b.data)
            .filter(|(x, y)| **x && !**y)
            .count()
    }

    #[test]
    fn a_pixel_goes_to_the_nearest_rope_and_serves_it_only_in_its_colour() {
        let r = 0.003;
        let a = along_x(-0.005, 0.597);
        let b = along_x(0.005, 0.597);
        let both = Scene::new(&[(&a, r), (&b, r)]);
        let frame = both.frame();
        // Rope `a`'s colour range takes every rope pixel (a range picked
        // wide), rope `b`'s only those of the right half (picked narrow).
        let wide = both.mask.clone();
        let mut narrow = both.mask.clone();
        for (i, p) in narrow.data.iter_mut().enumerate() {
            *p &= (i % W as usize) >= (W / 2) as usize;
        }
        let lines = [tracked(&a, r), tracked(&b, r)];
        let shares = share_pixels(&frame, &camera(), &[&wide, &narrow], &lines, 0.04);
        // `b`'s pixels of the left half, which only `a`'s range accepts,
        // are still not `a`'s: `a` keeps its own side only.
        assert_eq!(misassigned(&both, &shares[0].own, &a, &b), 0);
        assert_eq!(misassigned(&both, &shares[1].own, &b, &a), 0);
        assert_eq!(
            outside(&shares[1].own, &narrow),
            0,
            "b uses its colour only"
        );
        assert!(shares[0].own.count() * 10 > both.mask.count() * 4);
        assert!(shares[1].own.count() * 10 > both.mask.count() * 2);
        // Ropes of colours that never meet keep their whole colour masks.
        let far = along_x(0.05, 0.597);
        let (scene_a, scene_far) = (Scene::new(&[(&a, r)]), Scene::new(&[(&far, r)]));
        let apart = Scene::new(&[(&a, r), (&far, r)]);
        let lines = [tracked(&a, r), tracked(&far, r)];
        let frame = apart.frame();
        let shares = share_pixels(
            &frame,
            &camera(),
            &[&scene_a.mask, &scene_far.mask],
            &lines,
            0.04,
        );
        assert_eq!(shares[0].own, scene_a.mask);
        assert_eq!(shares[1].own, scene_far.mask);
    }

    #[test]
    fn a_mask_of_another_size_or_no_ropes_does_not_panic() {
        let rgb = vec![0u8; (W * H * 3) as usize];
        let depth = vec![0u16; (W * H) as usize];
        let frame = Frame::new(W, H, &rgb, &depth, 0.001).expect("frame");
        let small = Mask::new(4, 4);
        let nan = [Vec3::new(f64::NAN, 0.0, 0.5), Vec3::new(0.0, 0.0, 0.5)];
        let lines = [Some(RopeLine {
            nodes: &nan,
            radius: 0.003,
        })];
        let shares = share_pixels(&frame, &camera(), &[&small], &lines, 0.04);
        assert_eq!(shares[0].own.count(), 0);
        assert!(share_pixels(&frame, &camera(), &[], &[], 0.04).is_empty());
    }
}
