//! Initialisation without a learned model: the rope found among whatever
//! the colour range selects. Each shape of the mask is thinned to a
//! skeleton (`skeleton.rs`), walked the way a rope goes, straight on through
//! each junction with the least bending (`graph.rs`), cut where its width or
//! depth jumps (a rope touching a phone, two things overlapping in the
//! image), and each piece is tested as a rope would be: thin, of even
//! width, long, smooth. The pieces that pass are joined end to end where
//! their ends are close and point at each other (`candidates.rs`); one
//! candidate is chosen (the one the user clicked, the one nearest the last
//! known state after a loss, else the longest), lifted to 3D with the
//! strand on top at each crossing (`lift.rs`), and `M` nodes are placed
//! evenly along it. `docs/algorithm-notes.md`, "Finding the rope", gives
//! the reasons for each rule.

mod candidates;
mod cross_section;
mod graph;
mod lift;
mod report;
mod runs;
mod skeleton;

use alloc::vec::Vec;

use candidates::{join, rope_pieces, Chain, Joins, Metric};
pub use candidates::{
    one_rope_thick, DIAMETER_PRIOR_FACTOR, EVEN_TOLERANCE, JOIN_DIAMETER_RATIO, JOIN_GAP_DIAMETERS,
    JOIN_GAP_FRACTION, MAX_JOIN_ANGLE_DEGREES, MAX_TURN_PER_WIDTH_DEGREES, MIN_EVEN_SHARE,
    MIN_FRAGMENT_ELONGATION, MIN_ROPE_ELONGATION, ROPE_DIAMETER_RANGE, THICK_RATIO, WIDTH_SLACK_PX,
};
pub use cross_section::{
    mask_cover, strip_depth_ratio, strip_push, BACKGROUND_FROM_HALF_WIDTHS,
    BACKGROUND_TO_HALF_WIDTHS, MAX_SECTION_SAMPLES, MIN_SECTION_HALF_WIDTH_PX, MIN_SECTION_SAMPLES,
    SECTION_CONTRAST_SIGMAS,
};
pub use graph::{MAX_CROSSING_TURN_DEGREES, MAX_JUNCTION_CELLS};
use lift::{line_through, resolve_crossings};
pub use report::{Candidate, ChoiceRule, InitReport, NotRope, SetAside};
pub use skeleton::{MAX_SHAPES, SPUR_DISCS};

use super::camera::CameraIntrinsics;
use super::frame::Frame;
use super::point_cloud::CloudSettings;
use super::segmentation::Mask;
use crate::math::{Vec2, Vec3};
use crate::polyline::{distance_to_polyline, polyline_length, resample_uniform};

/// Fewest pixels on a centre line worth initialising from.
pub const MIN_CENTRE_LINE_PIXELS: usize = 8;
/// Shapes smaller than this many pixels are specks, not looked at.
pub const MIN_SHAPE_PIXELS: usize = 12;
/// A candidate longer than this multiple of a prior length is not the rope.
pub const PRIOR_LENGTH_FACTOR: f64 = 1.25;
/// A click chooses the candidate passing within this many of its widths of
/// it (and at least [`MIN_HINT_REACH_PX`]).
pub const HINT_REACH_WIDTHS: f64 = 3.0;
/// Nearest reach of a click, pixels.
pub const MIN_HINT_REACH_PX: f64 = 8.0;
/// Shapes set aside that a report lists (the largest first).
pub const MAX_REPORTED_SET_ASIDE: usize = 8;

/// Why no rope could be found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InitError {
    /// Nothing in the colour range large enough to be the rope.
    #[error("no rope in view: the largest shape in the colour range has {largest} pixels, at least {min} needed")]
    NoRope {
        /// Pixels in the largest shape.
        largest: usize,
        /// The `min_blob_pixels` parameter.
        min: u32,
    },
    /// Shapes in the colour range, none of them rope-shaped.
    #[error("nothing rope-shaped in view: {shapes} shape(s) in the colour range, none thin, even and long; the largest, {largest}")]
    NothingRopeShaped {
        /// Shapes looked at.
        shapes: usize,
        /// The largest, and why it is not a rope.
        largest: SetAside,
    },
    /// The centre line found is too short.
    #[error("centre line too short: {pixels} pixels")]
    TooShort {
        /// Pixels on it.
        pixels: usize,
    },
    /// No valid depth anywhere along the centre line.
    #[error("no valid depth along the rope's centre line")]
    NoDepth,
    /// Every rope-shaped candidate is one of the other ropes tracked.
    #[error("every rope-shaped candidate ({candidates}) is another rope already tracked")]
    AllTaken {
        /// Candidates looked at.
        candidates: usize,
    },
}

/// Another rope tracked in the same frame, as initialisation sees it: a
/// candidate lying along it is that rope, not this one.
#[derive(Debug, Clone, PartialEq)]
pub struct TakenRope {
    /// Its nodes projected into the image, pixels.
    pub line: Vec<Vec2>,
    /// Its radius in the image, pixels.
    pub radius_px: f64,
}

impl TakenRope {
    /// `true` when more than half of `points` (a candidate's centre line,
    /// pixels) lie within this rope's radius of its projected axis: two
    /// ropes' axes are never closer than the sum of their radii, except
    /// where one crosses over the other.
    pub fn covers(&self, points: &[Vec2]) -> bool {
        // A rope seen at one point has no axis to lie along.
        if self.line.len() < 2 {
            return false;
        }
        let reach = self.radius_px.max(MIN_TAKEN_REACH_PX);
        let on = points
            .iter()
            .filter(|p| distance_to_polyline(*p, &self.line).is_some_and(|d| d <= reach))
            .count();
        2 * on > points.len()
    }
}

/// Smallest reach of [`TakenRope::covers`], pixels: a thin rope's axis is
/// found to about a pixel.
pub const MIN_TAKEN_REACH_PX: f64 = 1.5;

/// Why a rope is invalid as a prior.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PriorError {
    /// A length that is not positive and finite.
    #[error("the rope's {field} must be a positive length in metres, got {value}")]
    NotALength {
        /// `length_m` or `diameter_m`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
}

/// What the user knows of the rope (`dlo.json`'s `rope`), both optional.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RopePrior {
    /// Length, metres: candidates longer than [`PRIOR_LENGTH_FACTOR`] times
    /// it are not the rope, and a re-initialisation is judged against it.
    pub length: Option<f64>,
    /// Diameter, metres: a piece is rope only within
    /// [`DIAMETER_PRIOR_FACTOR`] of it, and it is the radius in force.
    pub diameter: Option<f64>,
}

impl RopePrior {
    /// Checks that each length given is positive and finite.
    pub fn validate(&self) -> Result<(), PriorError> {
        for (field, value) in [("length_m", self.length), ("diameter_m", self.diameter)] {
            if let Some(v) = value {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(PriorError::NotALength { field, value: v });
                }
            }
        }
        Ok(())
    }
}

/// What guides the choice among the candidates.
#[derive(Debug, Clone, Copy, Default)]
pub struct InitGuide<'a> {
    /// What the user knows of the rope.
    pub prior: RopePrior,
    /// A pixel the user clicked on the rope.
    pub hint: Option<Vec2>,
    /// The last known nodes, after a loss: the candidate nearest them is
    /// taken, among those of at least `min_length`.
    pub previous: &'a [Vec3],
    /// Shortest candidate worth taking near `previous`, metres.
    pub min_length: f64,
    /// The other ropes tracked in this frame: candidates along them are
    /// theirs.
    pub taken: &'a [TakenRope],
    /// Other ropes of this rope's colour may be in view: piece ends that
    /// meet only at a corner may be two ropes' and are not joined (a
    /// rope alone is one rope kinked there).
    pub alike_ropes: bool,
}

/// A fresh set of nodes for the rope in this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Initialisation {
    /// `M` nodes evenly spaced along the centre line.
    pub nodes: Vec<Vec3>,
    /// Length of the centre line, metres.
    pub length: f64,
    /// The rope's radius estimated from its mask's width in the image,
    /// metres (`None` when not asked for or not measurable): the half width
    /// of the strip the colour range covers.
    pub radius: Option<f64>,
    /// The share of the rope's width its mask covers, as the depth image
    /// shows it ([`mask_cover`]; `None` where not measured): the rope's
    /// radius is `radius` over it.
    pub mask_cover: Option<f64>,
    /// What was found and why this was taken.
    pub report: InitReport,
}

impl Initialisation {
    /// The diameter of the candidate taken, as the rope test measured it
    /// (median width at its median depth), metres.
    pub fn diameter(&self) -> Option<f64> {
        self.report
            .candidates
            .get(self.report.chosen)
            .map(|c| c.diameter)
    }
}

/// Smallest radius an estimate may give, metres (a thread).
pub const MIN_ESTIMATED_RADIUS: f64 = 0.0005;
/// Largest radius an estimate may give, metres (a hose).
pub const MAX_ESTIMATED_RADIUS: f64 = 0.05;

/// The rope's radius from its mask: the mean width in pixels (its pixels
/// over the centre line's length in pixels) at the median depth of the
/// centre line, `r = w z / (2 f)`. `None` outside the plausible range.
pub fn estimate_radius(
    blob_pixels: usize,
    path: &[Vec2],
    line: &[Vec3],
    camera: &CameraIntrinsics,
) -> Option<f64> {
    let half_px = mask_half_width_px(blob_pixels, path);
    if !(half_px > 0.0) || line.is_empty() {
        return None;
    }
    let mut z: Vec<f64> = line.iter().map(|p| p.z).filter(|z| z.is_finite()).collect();
    if z.is_empty() {
        return None;
    }
    z.sort_by(f64::total_cmp);
    let r = half_px * z[z.len() / 2] / (0.5 * (camera.fx + camera.fy));
    (MIN_ESTIMATED_RADIUS..=MAX_ESTIMATED_RADIUS)
        .contains(&r)
        .then_some(r)
}

/// Half the mean width of a mask of `blob_pixels` along `path`, pixels
/// (0 for a path without length).
fn mask_half_width_px(blob_pixels: usize, path: &[Vec2]) -> f64 {
    let length_px: f64 = path.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    if length_px > 0.0 {
        0.5 * blob_pixels as f64 / length_px
    } else {
        0.0
    }
}

/// What initialisation needs from the parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitSettings {
    /// Nodes to place (`M`); the fewest when `node_spacing_diameters` sets
    /// the count from the rope found.
    pub node_count: usize,
    /// Nodes this many of the rope's diameters apart, when its diameter is
    /// known (the prior's, or measured with `estimate_radius`): see
    /// [`node_count_for`]. 0 places `node_count` whatever the rope.
    pub node_spacing_diameters: f64,
    /// Fewest mask pixels taken as the rope.
    pub min_blob_pixels: u32,
    /// Depth range and the surface-to-axis push of the 3D lift.
    pub cloud: CloudSettings,
    /// Estimate the radius from the image and push the line by it instead
    /// of by `cloud.axis_offset`.
    pub estimate_radius: bool,
}

/// The pixels of the largest 8-connected shape of `mask`, in image order.
pub fn largest_blob(mask: &Mask) -> Vec<usize> {
    let (shapes, _) = skeleton::shapes(mask, 1);
    shapes
        .into_iter()
        .next()
        .map_or_else(Vec::new, |s| s.pixels)
}

/// The candidates and what was set aside, from the whole mask.
struct Found {
    chains: Vec<Chain>,
    set_aside: Vec<SetAside>,
    shapes: usize,
    largest: usize,
}

fn find(
    mask: &Mask,
    metric: Option<Metric<'_>>,
    settings_min_pixels: u32,
    prior: RopePrior,
    joins: Joins,
) -> Found {
    let (shapes, labels) = skeleton::shapes(mask, MIN_SHAPE_PIXELS);
    let largest = shapes.first().map_or(0, |s| s.pixels.len());
    let (pieces, mut set_aside) = rope_pieces(&shapes, &labels, mask, metric, prior.diameter);
    let mut chains = join(&pieces, metric.is_some(), joins);
    chains.sort_by(|a, b| b.length.total_cmp(&a.length));
    let centre = |c: &Chain| {
        let n = c.points.len().max(1) as f64;
        let s = c.points.iter().fold(Vec2::zeros(), |a, p| a + p);
        [s.x / n, s.y / n]
    };
    chains.retain(|c| {
        let elongation = c.length / c.diameter;
        let reason = if !(elongation >= MIN_ROPE_ELONGATION) {
            Some(NotRope::Short { elongation })
        } else if c.pixels < f64::from(settings_min_pixels) {
            Some(NotRope::Small {
                pixels: c.pixels as usize,
            })
        } else {
            match (metric, prior.length) {
                (Some(_), Some(l)) if c.length > PRIOR_LENGTH_FACTOR * l => {
                    Some(NotRope::LongerThanPrior {
                        length_m: c.length,
                        prior_m: l,
                    })
                }
                _ => None,
            }
        };
        if let Some(reason) = reason {
            set_aside.push(SetAside {
                pixels: c.pixels as usize,
                centre: centre(c),
                reason,
            });
        }
        reason.is_none()
    });
    set_aside.sort_by_key(|s| core::cmp::Reverse(s.pixels));
    Found {
        chains,
        set_aside,
        shapes: shapes.len(),
        largest,
    }
}

impl Found {
    /// The error when no candidate is left.
    fn nothing(&self, min: u32) -> InitError {
        match self.set_aside.first() {
            Some(&largest) if self.largest >= min as usize => InitError::NothingRopeShaped {
                shapes: self.shapes,
                largest,
            },
            _ => InitError::NoRope {
                largest: self.largest,
                min,
            },
        }
    }

    /// The candidate to take, and why.
    fn choose(&self, guide: &InitGuide<'_>) -> Result<(usize, ChoiceRule, bool), InitError> {
        let free: Vec<bool> = self
            .chains
            .iter()
            .map(|c| !guide.taken.iter().any(|t| t.covers(&c.points)))
            .collect();
        let Some(first_free) = free.iter().position(|&f| f) else {
            return Err(InitError::AllTaken {
                candidates: self.chains.len(),
            });
        };
        let mut hint_missed = false;
        if let Some(h) = guide.hint {
            let near = self
                .chains
                .iter()
                .enumerate()
                .filter(|(k, _)| free[*k])
                .map(|(k, c)| {
                    let d = c
                        .points
                        .iter()
                        .map(|p| (p - h).norm())
                        .fold(f64::MAX, f64::min);
                    let width = c.pixels / c.length_px().max(1.0);
                    (k, d, (HINT_REACH_WIDTHS * width).max(MIN_HINT_REACH_PX))
                })
                .filter(|&(_, d, reach)| d <= reach)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match near {
                Some((k, _, _)) => return Ok((k, ChoiceRule::Clicked, false)),
                None => hint_missed = true,
            }
        }
        if !guide.previous.is_empty() {
            let nearest = self
                .chains
                .iter()
                .enumerate()
                .filter(|(k, c)| free[*k] && c.length >= guide.min_length)
                .map(|(k, c)| (k, mean_distance(guide.previous, &c.line)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, _)) = nearest {
                return Ok((k, ChoiceRule::NearestPrevious, hint_missed));
            }
        }
        let rule = if free.iter().filter(|&&f| f).count() == 1 {
            ChoiceRule::Only
        } else {
            ChoiceRule::Longest
        };
        Ok((first_free, rule, hint_missed))
    }
}

/// Mean distance from each of `nodes` to the nearest of (at most 256 of) `line`'s points.
fn mean_distance(nodes: &[Vec3], line: &[Vec3]) -> f64 {
    let stride = line.len().div_ceil(256).max(1);
    let sum: f64 = nodes
        .iter()
        .map(|n| {
            line.iter()
                .step_by(stride)
                .map(|p| (p - n).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .sum();
    sum / nodes.len().max(1) as f64
}

/// The rope's centre line in the image: an ordered list of pixel positions
/// along the longest rope-shaped candidate of `mask` (judged in the image
/// alone, without depth). The end with the smaller x (then smaller y)
/// comes first.
pub fn find_centre_line(mask: &Mask, min_blob_pixels: u32) -> Result<Vec<Vec2>, InitError> {
    let found = find(
        mask,
        None,
        min_blob_pixels,
        RopePrior::default(),
        Joins::default(),
    );
    let Some(chain) = found.chains.first() else {
        return Err(found.nothing(min_blob_pixels));
    };
    let mut path = chain.points.clone();
    if path.len() < MIN_CENTRE_LINE_PIXELS {
        return Err(InitError::TooShort { pixels: path.len() });
    }
    let (first, last) = (path[0], path[path.len() - 1]);
    if (last.x, last.y) < (first.x, first.y) {
        path.reverse();
    }
    Ok(path)
}

/// Most nodes [`node_count_for`] places: every per-frame cost grows with
/// the count, and twice the paper's `M` = 24 already resolves bends a few
/// centimetres across on a 1.5 m rope (31 mm apart).
pub const MAX_SPACED_NODES: usize = 48;

/// The node count for a rope `length` long and `diameter` thick:
/// `round(L / (k d)) + 1` nodes for `k = node_spacing_diameters`, between
/// `node_count` and [`MAX_SPACED_NODES`] (`node_count` when it is larger,
/// `k` is 0 or the diameter unknown). A fixed count spaces a 1.5 m rope's
/// nodes five times as far apart as a 0.3 m rope's, and a polyline cuts
/// each bend by a share of its spacing squared; the spacing cannot fall
/// far below the rope's width either, or EM's round Gaussians settle on
/// either side of the axis in turn and the polyline zigzags
/// (`docs/algorithm-notes.md`, "The node count from the rope").
pub fn node_count_for(settings: &InitSettings, length: f64, diameter: Option<f64>) -> usize {
    let least = settings.node_count;
    let k = settings.node_spacing_diameters;
    let Some(d) = diameter.filter(|d| *d > 0.0 && d.is_finite()) else {
        return least;
    };
    if !(k > 0.0) || !(length > 0.0) || !length.is_finite() {
        return least;
    }
    let spaced = libm::round(length / (k * d)) + 1.0;
    (spaced.min(MAX_SPACED_NODES as f64) as usize).max(least)
}

/// The rope's whole diameter, metres, when known: the prior's, else the
/// measured `mask_radius` (the strip its mask covers) over the share
/// `cover` of the width that strip is.
pub fn whole_diameter(
    prior: Option<f64>,
    mask_radius: Option<f64>,
    cover: Option<f64>,
) -> Option<f64> {
    prior.or(mask_radius.map(|r| 2.0 * r / cover.unwrap_or(1.0)))
}

/// The whole stage: candidates, the choice, the 3D lift, even placement of `M` nodes.
pub fn initialise(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &InitSettings,
    guide: &InitGuide<'_>,
) -> Result<Initialisation, InitError> {
    let metric = Metric {
        frame,
        camera,
        cloud: &settings.cloud,
    };
    let joins = Joins {
        corners: !guide.alike_ropes,
    };
    let found = find(
        mask,
        Some(metric),
        settings.min_blob_pixels,
        guide.prior,
        joins,
    );
    if found.chains.is_empty() {
        return Err(found.nothing(settings.min_blob_pixels));
    }
    let (chosen, rule, hint_missed) = found.choose(guide)?;
    let chain = &found.chains[chosen];
    let (mut path, mut zones, mut depths) = (
        chain.points.clone(),
        chain.zones.clone(),
        chain.depths.clone(),
    );
    if path.len() < MIN_CENTRE_LINE_PIXELS {
        return Err(InitError::TooShort { pixels: path.len() });
    }
    let (first, last) = (path[0], path[path.len() - 1]);
    if (last.x, last.y) < (first.x, first.y) {
        path.reverse();
        zones.reverse();
        depths.reverse();
    }
    resolve_crossings(&mut depths, &zones);
    let mut line = line_through(&path, &depths, camera, settings.cloud.axis_offset)
        .ok_or(InitError::NoDepth)?;
    let (mut radius, mut cover) = (None, None);
    if settings.estimate_radius {
        radius = estimate_radius(chain.pixels as usize, &path, &line, camera);
        if let Some(r) = radius {
            let half_px = mask_half_width_px(chain.pixels as usize, &path);
            cover = mask_cover(frame, mask, camera, &settings.cloud, &path, &zones, half_px);
            let c = cover.unwrap_or(1.0);
            // Lift again, pushed to the axis of a rope this wide.
            line = line_through(&path, &depths, camera, strip_push(r / c, c))
                .ok_or(InitError::NoDepth)?;
        }
    }
    let length = polyline_length(&line);
    if !(length > 0.0) || !length.is_finite() {
        return Err(InitError::TooShort { pixels: path.len() });
    }
    let candidates = found
        .chains
        .iter()
        .map(|c| {
            let (a, b) = (c.points[0], c.points[c.points.len() - 1]);
            Candidate {
                length: c.length,
                diameter: c.diameter,
                fragments: c.fragments,
                crossings: c.crossings,
                ends: [[a.x, a.y], [b.x, b.y]],
            }
        })
        .collect();
    let report = InitReport {
        candidates,
        chosen,
        rule,
        set_aside_count: found.set_aside.len(),
        set_aside: found
            .set_aside
            .iter()
            .take(MAX_REPORTED_SET_ASIDE)
            .copied()
            .collect(),
        hint_missed,
        prior_length_ratio: guide.prior.length.map(|l| length / l),
    };
    let diameter = whole_diameter(guide.prior.diameter, radius, cover);
    let count = node_count_for(settings, length, diameter);
    Ok(Initialisation {
        nodes: resample_uniform(&line, count),
        length,
        radius,
        mask_cover: cover,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule a recovery is judged by (drawn scene 1032 with the
    /// simulator's version 3: a box's dark edge 8.2 mm thick beside a
    /// 4.4 mm rope was taken for it).
    #[test]
    fn a_recovery_takes_only_a_rope_as_thick_as_the_one_tracked() {
        assert!(!one_rope_thick(8.2e-3, 4.4e-3));
        assert!(!one_rope_thick(4.4e-3, 8.2e-3));
        assert!(one_rope_thick(5.5e-3, 4.4e-3));
        assert!(one_rope_thick(4.4e-3, 4.4e-3 * 0.99 * JOIN_DIAMETER_RATIO));
        // Unmeasured: never one rope.
        assert!(!one_rope_thick(0.0, 4.4e-3));
        assert!(!one_rope_thick(f64::NAN, 4.4e-3));
    }
    use alloc::vec;

    #[test]
    fn the_node_count_spaces_nodes_by_the_ropes_diameter_within_its_bounds() {
        let spaced = InitSettings {
            node_spacing_diameters: 4.0,
            ..crate::Params::default().init()
        };
        // 1.2 m, 10 mm thick: 40 mm apart, 31 nodes.
        assert_eq!(node_count_for(&spaced, 1.2, Some(0.010)), 31);
        // A short thick rope keeps the least count; a long thread the most.
        assert_eq!(node_count_for(&spaced, 0.3, Some(0.020)), 24);
        assert_eq!(node_count_for(&spaced, 1.5, Some(0.003)), MAX_SPACED_NODES);
        // Unknown diameter, spacing off, or a bad length: the fixed count.
        let fixed = InitSettings {
            node_spacing_diameters: 0.0,
            ..spaced
        };
        assert_eq!(node_count_for(&fixed, 1.2, Some(0.010)), 24);
        for (length, diameter) in [
            (1.2, None),
            (f64::NAN, Some(0.01)),
            (1.2, Some(f64::NAN)),
            (-1.0, Some(0.01)),
            (f64::INFINITY, Some(0.01)),
            (1.2, Some(0.0)),
        ] {
            assert_eq!(node_count_for(&spaced, length, diameter), 24);
        }
        // A least count above the cap stands.
        let many = InitSettings {
            node_count: 100,
            ..spaced
        };
        assert_eq!(node_count_for(&many, 1.5, Some(0.003)), 100);
    }

    #[test]
    fn a_candidate_along_a_tracked_rope_is_taken_and_one_crossing_it_is_not() {
        let taken = TakenRope {
            line: (0..=10).map(|i| Vec2::new(10.0 * i as f64, 50.0)).collect(),
            radius_px: 3.0,
        };
        let along: Vec<Vec2> = (0..60).map(|i| Vec2::new(10.0 + i as f64, 51.5)).collect();
        let across: Vec<Vec2> = (0..60).map(|i| Vec2::new(40.0, 20.0 + i as f64)).collect();
        let beside: Vec<Vec2> = (0..60).map(|i| Vec2::new(10.0 + i as f64, 58.0)).collect();
        assert!(taken.covers(&along));
        assert!(
            !taken.covers(&across),
            "a crossing shares a few pixels only"
        );
        assert!(!taken.covers(&beside), "a rope lying beside it is another");
        assert!(!taken.covers(&[]));
    }

    /// Draws a thick polyline (disc brush) into a mask.
    fn draw(mask: &mut Mask, curve: &[Vec2], radius: f64) {
        for w in curve.windows(2) {
            let steps = ((w[1] - w[0]).norm() * 2.0) as usize + 1;
            for s in 0..=steps {
                let p = w[0] + (w[1] - w[0]) * (s as f64 / steps as f64);
                let r = radius as i64 + 1;
                for dv in -r..=r {
                    for du in -r..=r {
                        let (u, v) = (libm::round(p.x) as i64 + du, libm::round(p.y) as i64 + dv);
                        let q = Vec2::new(u as f64, v as f64);
                        let inside =
                            u >= 0 && v >= 0 && u < mask.width as i64 && v < mask.height as i64;
                        if inside && (q - p).norm() <= radius {
                            mask.data[(v * mask.width as i64 + u) as usize] = true;
                        }
                    }
                }
            }
        }
    }

    fn curve(f: impl Fn(f64) -> Vec2) -> Vec<Vec2> {
        (0..=400).map(|i| f(i as f64 / 400.0)).collect()
    }

    /// Checks that `line` runs from one end of `truth` to the other, in order.
    fn assert_follows(line: &[Vec2], truth: &[Vec2], tol: f64) {
        let (a, b) = (truth[0], truth[truth.len() - 1]);
        let (s, e) = (line[0], line[line.len() - 1]);
        let direct = (s - a).norm().max((e - b).norm());
        let swapped = (s - b).norm().max((e - a).norm());
        assert!(direct.min(swapped) < tol, "ends {s:?} {e:?} vs {a:?} {b:?}");
        let truth: Vec<Vec2> = if direct <= swapped {
            truth.to_vec()
        } else {
            truth.iter().rev().copied().collect()
        };
        // Each line point lies on the curve, and the index of its nearest
        // truth sample never goes back by more than a rope width.
        let mut last = 0usize;
        for p in line {
            let (k, d) = truth
                .iter()
                .enumerate()
                .map(|(k, q)| (k, (p - q).norm()))
                .fold((0, f64::MAX), |best, x| if x.1 < best.1 { x } else { best });
            assert!(d < tol, "point {p:?} is {d} px off the curve");
            assert!(k + 10 >= last, "order goes back at {p:?}");
            last = last.max(k);
        }
    }

    #[test]
    fn straight_u_and_s_shapes_with_noise_blobs() {
        let shapes: [Vec<Vec2>; 3] = [
            curve(|t| Vec2::new(60.0 + 500.0 * t, 240.0 + 30.0 * t)),
            curve(|t| {
                let a = core::f64::consts::PI * t;
                Vec2::new(
                    320.0 + 150.0 * libm::sin(a) - 100.0 * (1.0 - t),
                    240.0 - 150.0 * libm::cos(a),
                )
            }),
            curve(|t| {
                let a = core::f64::consts::TAU * t;
                Vec2::new(100.0 + 440.0 * t, 240.0 + 120.0 * libm::sin(a))
            }),
        ];
        for shape in &shapes {
            let mut mask = Mask::new(640, 480);
            draw(&mut mask, shape, 7.0);
            // Noise: small blobs that must be ignored.
            draw(
                &mut mask,
                &[Vec2::new(20.0, 20.0), Vec2::new(24.0, 22.0)],
                3.0,
            );
            draw(
                &mut mask,
                &[Vec2::new(600.0, 450.0), Vec2::new(601.0, 450.0)],
                4.0,
            );
            let line = find_centre_line(&mask, 150).expect("centre line");
            // The blob, drawn with a disc, reaches one radius past the curve's ends.
            assert_follows(&line, shape, 9.0);
        }
    }

    #[test]
    fn a_rope_with_a_ragged_edge_is_one_candidate_round_its_bends() {
        // A rope 11 px wide whose texture's dark stripes cut a slit a pixel
        // in from its edge every 5 px, alternately on each side, leaving
        // slivers along the edge (a grey rope: drawn scene 1009 was found
        // in two pieces cut at its bend).
        let rope: Vec<Vec2> = curve(|t| {
            let a = 1.5 * core::f64::consts::TAU * t;
            Vec2::new(120.0 + 400.0 * t, 240.0 + 110.0 * libm::sin(a))
        });
        let mut mask = Mask::new(640, 480);
        draw(&mut mask, &rope, 5.5);
        let mut along = 0.0;
        let mut next = 0.0;
        let mut side = 1.0;
        for w in rope.windows(2) {
            along += (w[1] - w[0]).norm();
            if along < next {
                continue;
            }
            next += 5.0;
            side = -side;
            let d = (w[1] - w[0]) / (w[1] - w[0]).norm();
            let normal = Vec2::new(-d.y, d.x) * side;
            // A slit 3 px along the edge, 4.5 px out from the axis.
            for across in [-1.0, 0.0, 1.0] {
                let q = w[0] + normal * 4.5 + d * across;
                let (u, v) = (libm::round(q.x) as usize, libm::round(q.y) as usize);
                mask.data[v * 640 + u] = false;
            }
        }
        assert_eq!(skeleton::shapes(&mask, 1).0.len(), 1, "still one shape");
        let found = find(&mask, None, 150, RopePrior::default(), Joins::default());
        assert_eq!(found.chains.len(), 1, "{} candidates", found.chains.len());
        // Within a rope's width: the tip's extension follows a ragged end.
        assert_follows(&found.chains[0].points, &rope, 11.0);
    }

    #[test]
    fn empty_and_tiny_masks_are_errors() {
        let mask = Mask::new(64, 48);
        assert!(matches!(
            find_centre_line(&mask, 10),
            Err(InitError::NoRope { largest: 0, .. })
        ));
        // A speck is not even looked at.
        let mut mask = Mask::new(64, 48);
        mask.data[100] = true;
        assert!(matches!(
            find_centre_line(&mask, 1),
            Err(InitError::NoRope { largest: 0, .. })
        ));
    }

    /// A flat scene at 0.6 m (depth in millimetres) and the default settings.
    struct Scene {
        mask: Mask,
        depth: Vec<u16>,
        rgb: Vec<u8>,
    }

    impl Scene {
        fn new() -> Self {
            Self {
                mask: Mask::new(640, 480),
                depth: vec![600; 640 * 480],
                rgb: vec![0; 640 * 480 * 3],
            }
        }

        /// Draws `curve` with a disc of `radius` pixels at `depth_mm`.
        fn draw(&mut self, curve: &[Vec2], radius: f64, depth_mm: u16) {
            let before = self.mask.data.clone();
            draw(&mut self.mask, curve, radius);
            for (i, (&b, &a)) in before.iter().zip(&self.mask.data).enumerate() {
                if a && !b {
                    self.depth[i] = depth_mm;
                }
            }
            // Where it lies over pixels already set, it is on top.
            let mut top = Mask::new(640, 480);
            draw(&mut top, curve, radius);
            for (i, &t) in top.data.iter().enumerate() {
                if t {
                    self.depth[i] = self.depth[i].min(depth_mm);
                }
            }
        }

        fn initialise(&self, guide: &InitGuide<'_>) -> Result<Initialisation, InitError> {
            let frame = Frame::new(640, 480, &self.rgb, &self.depth, 0.001).expect("frame");
            let settings = crate::params::Params::default().init();
            initialise(
                &frame,
                &self.mask,
                &CameraIntrinsics::D435I_640X480,
                &settings,
                guide,
            )
        }
    }

    /// The image of `nodes` (metres) in the test camera.
    fn projected(nodes: &[Vec3]) -> Vec<Vec2> {
        let cam = CameraIntrinsics::D435I_640X480;
        nodes
            .iter()
            .map(|n| Vec2::new(cam.fx * n.x / n.z + cam.cx, cam.fy * n.y / n.z + cam.cy))
            .collect()
    }

    fn px_length(c: &[Vec2]) -> f64 {
        c.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
    }

    /// An S curve 5 px wide (a thin cable, 5 mm at 0.6 m).
    fn cable() -> Vec<Vec2> {
        curve(|t| {
            let a = core::f64::consts::TAU * t;
            Vec2::new(330.0 + 280.0 * t, 240.0 + 80.0 * libm::sin(a))
        })
    }

    #[test]
    fn a_thin_cable_wins_over_a_larger_phone() {
        let mut scene = Scene::new();
        // A phone, 72 x 150 px (7 x 15 cm at 0.6 m), 8 mm proud of the table.
        let phone = [Vec2::new(120.0, 170.0), Vec2::new(120.0, 310.0)];
        scene.draw(&phone, 36.0, 592);
        scene.draw(&cable(), 2.5, 598);
        // The phone is the largest blob: the old rule took it.
        let blob = largest_blob(&scene.mask);
        assert!(
            blob.iter().any(|&i| i % 640 < 200),
            "phone is not the largest"
        );
        let init = scene.initialise(&InitGuide::default()).expect("rope found");
        assert_follows(&projected(&init.nodes), &cable(), 6.0);
        let truth = px_length(&cable()) * 0.6 / 615.0;
        assert!(
            (init.length / truth - 1.0).abs() < 0.05,
            "length {} of {truth}",
            init.length
        );
        assert_eq!(init.report.candidates.len(), 1, "{}", init.report);
        assert!(
            init.report
                .set_aside
                .iter()
                .any(|s| s.centre[0] < 200.0 && s.pixels > 10_000),
            "the phone is not reported: {}",
            init.report
        );
    }

    #[test]
    fn a_thin_cable_touching_a_phone_is_cut_from_it() {
        let mut scene = Scene::new();
        // Its bottom edge lies over the cable's middle.
        let phone = [Vec2::new(470.0, 110.0), Vec2::new(470.0, 206.0)];
        scene.draw(&phone, 36.0, 592);
        scene.draw(&cable(), 2.5, 598);
        assert_eq!(skeleton::shapes(&scene.mask, 1).0.len(), 1, "not touching");
        let init = scene.initialise(&InitGuide::default()).expect("rope found");
        assert_follows(&projected(&init.nodes), &cable(), 6.0);
    }

    #[test]
    fn a_curve_in_three_fragments_is_one_rope() {
        let mut scene = Scene::new();
        let rope = cable();
        scene.draw(&rope, 2.5, 598);
        // Two pens across it, 10 px wide: three pieces of mask.
        for x in [420.0, 520.0] {
            for v in 0..480usize {
                for u in (x as usize - 5)..(x as usize + 5) {
                    scene.mask.data[v * 640 + u] = false;
                }
            }
        }
        assert_eq!(skeleton::shapes(&scene.mask, 1).0.len(), 3);
        let init = scene.initialise(&InitGuide::default()).expect("rope found");
        let chosen = init.report.candidates[init.report.chosen];
        assert_eq!(chosen.fragments, 3, "{}", init.report);
        let truth = px_length(&rope) * 0.6 / 615.0;
        assert!(
            (init.length / truth - 1.0).abs() < 0.05,
            "length {} of {truth}",
            init.length
        );
        assert_follows(&projected(&init.nodes), &rope, 6.0);
    }

    #[test]
    fn an_x_crossing_is_passed_straight_through() {
        let mut mask = Mask::new(640, 480);
        let a = curve(|t| Vec2::new(120.0 + 400.0 * t, 60.0 + 360.0 * t));
        let b = curve(|t| Vec2::new(140.0 + 360.0 * t, 420.0 - 360.0 * t));
        draw(&mut mask, &a, 7.0);
        draw(&mut mask, &b, 7.0);
        let line = find_centre_line(&mask, 150).expect("centre line");
        // Straight through: along one stroke from end to end, never into the other.
        let follows = |c: &[Vec2]| line.iter().all(|p| c.iter().any(|q| (p - q).norm() < 9.0));
        assert!(
            follows(&a) || follows(&b),
            "the path turned at the crossing"
        );
        assert!(px_length(&line) > 0.9 * px_length(&a).min(px_length(&b)));
    }

    /// A loop crossing itself (the nodal cubic `y^2 = x^2 (x + 1)`), the
    /// strand at `t = 1` 15 mm over the one at `t = -1`.
    fn alpha() -> Vec<Vec2> {
        curve(|s| {
            let t = -1.4 + 2.8 * s;
            Vec2::new(
                320.0 - 110.0 * (t * t - 1.0),
                240.0 + 110.0 * t * (t * t - 1.0),
            )
        })
    }

    #[test]
    fn a_loop_crossing_itself_is_followed_round_and_lifted_with_its_top_strand() {
        let mut scene = Scene::new();
        let rope = alpha();
        let n = rope.len();
        // The strand at t = 1 rises 15 mm as it passes over the other
        // (t = -1.4 + 2.8 s, so s = 6 / 7 at the crossing).
        let depth_mm = |k: usize| {
            let d = (k as f64 / (n - 1) as f64 - 6.0 / 7.0) / 0.12;
            let bump = if d.abs() < 1.0 {
                0.5 + 0.5 * libm::cos(core::f64::consts::PI * d)
            } else {
                0.0
            };
            600.0 - 15.0 * bump
        };
        for k in 1..n {
            scene.draw(&rope[k - 1..=k], 7.0, libm::round(depth_mm(k)) as u16);
        }
        let init = scene.initialise(&InitGuide::default()).expect("rope found");
        let nodes = projected(&init.nodes);
        assert_follows(&nodes, &rope, 9.0);
        // The true length, with a rope radius at each rounded tip.
        let cam = CameraIntrinsics::D435I_640X480;
        let at = |k: usize| cam.deproject(rope[k].x, rope[k].y, depth_mm(k) / 1000.0);
        let truth: f64 =
            (1..n).map(|k| (at(k) - at(k - 1)).norm()).sum::<f64>() + 2.0 * 7.0 * 0.6 / 615.0;
        assert!(
            (init.length / truth - 1.0).abs() < 0.05,
            "length {} of {truth} (the loop was cut off?)",
            init.length
        );
        let chosen = init.report.candidates[init.report.chosen];
        assert_eq!(chosen.crossings, 1, "{}", init.report);
        // The crossing is the image point (320, 240): the node of the lower
        // strand nearest it lies at the table's depth, not the top strand's.
        let near = |from: usize, to: usize| {
            (from..to)
                .min_by(|&a, &b| {
                    let d = |k: usize| (nodes[k] - Vec2::new(320.0, 240.0)).norm();
                    d(a).total_cmp(&d(b))
                })
                .expect("nodes")
        };
        let m = init.nodes.len();
        let (low, high) = if init.nodes[0].y < init.nodes[m - 1].y {
            (near(0, m / 2), near(m / 2, m))
        } else {
            (near(m / 2, m), near(0, m / 2))
        };
        assert!(
            init.nodes[high].z < init.nodes[low].z - 0.008,
            "top strand at {} m, lower at {} m",
            init.nodes[high].z,
            init.nodes[low].z
        );
    }

    /// Two loops in a row, each crossing the rope once: the path goes round
    /// both and through each crossing straight on.
    #[test]
    fn a_rope_with_two_crossings_is_followed_round_both_loops() {
        let mut mask = Mask::new(640, 480);
        let rope: Vec<Vec2> = (0..=800)
            .map(|i| {
                // Two nodal cubics side by side, joined by their tails.
                let s = i as f64 / 800.0;
                let (t, dx) = if s < 0.5 {
                    (-1.3 + 2.6 * (s / 0.5), 0.0)
                } else {
                    (-1.3 + 2.6 * ((s - 0.5) / 0.5), 0.0)
                };
                let x = -70.0 * (t * t - 1.0);
                let y = 70.0 * t * (t * t - 1.0);
                if s < 0.5 {
                    Vec2::new(200.0 + y + dx, 240.0 + x)
                } else {
                    Vec2::new(440.0 + y, 240.0 - x)
                }
            })
            .collect();
        draw(&mut mask, &rope, 6.0);
        let line = find_centre_line(&mask, 150).expect("centre line");
        // Both loops: the path is as long as the drawn rope (less its caps)
        // and passes the far side of each loop.
        let drawn = px_length(&rope);
        let found = px_length(&line);
        assert!(found > 0.9 * drawn, "{found:.0} px of {drawn:.0}");
        for far in [
            Vec2::new(200.0, 240.0 + 70.0),
            Vec2::new(440.0, 240.0 - 70.0),
        ] {
            let d = line
                .iter()
                .map(|p| (p - far).norm())
                .fold(f64::MAX, f64::min);
            assert!(d < 9.0, "the loop through {far:?} was left out ({d:.0} px)");
        }
    }

    #[test]
    fn nothing_rope_shaped_is_a_clear_error() {
        let mut scene = Scene::new();
        scene.draw(
            &[Vec2::new(120.0, 170.0), Vec2::new(120.0, 310.0)],
            36.0,
            592,
        );
        scene.draw(
            &[Vec2::new(400.0, 240.0), Vec2::new(401.0, 240.0)],
            40.0,
            590,
        );
        let err = scene
            .initialise(&InitGuide::default())
            .expect_err("no rope");
        let InitError::NothingRopeShaped { shapes, largest } = err else {
            panic!("{err}");
        };
        assert_eq!(shapes, 2);
        assert!(largest.pixels > 5000);
        let text = alloc::format!("{}", InitError::NothingRopeShaped { shapes, largest });
        assert!(text.starts_with("nothing rope-shaped in view"), "{text}");
    }

    #[test]
    fn a_click_or_the_last_state_chooses_among_candidates() {
        let mut scene = Scene::new();
        let long = cable();
        let short = curve(|t| Vec2::new(60.0 + 200.0 * t, 100.0 + 20.0 * t));
        scene.draw(&long, 2.5, 598);
        scene.draw(&short, 2.5, 598);
        let first = scene.initialise(&InitGuide::default()).expect("rope");
        assert_eq!(first.report.rule, ChoiceRule::Longest);
        assert_follows(&projected(&first.nodes), &long, 6.0);
        let clicked = scene
            .initialise(&InitGuide {
                hint: Some(Vec2::new(161.0, 111.0)),
                ..InitGuide::default()
            })
            .expect("rope");
        assert_eq!(clicked.report.rule, ChoiceRule::Clicked);
        assert_follows(&projected(&clicked.nodes), &short, 6.0);
        let missed = scene
            .initialise(&InitGuide {
                hint: Some(Vec2::new(300.0, 400.0)),
                ..InitGuide::default()
            })
            .expect("rope");
        assert!(missed.report.hint_missed && missed.report.rule == ChoiceRule::Longest);
        let again = scene
            .initialise(&InitGuide {
                previous: &clicked.nodes,
                min_length: 0.1,
                ..InitGuide::default()
            })
            .expect("rope");
        assert_eq!(again.report.rule, ChoiceRule::NearestPrevious);
        assert_follows(&projected(&again.nodes), &short, 6.0);
        // A length the short one does not reach leaves the long one.
        let longer = scene
            .initialise(&InitGuide {
                previous: &clicked.nodes,
                min_length: 0.3,
                ..InitGuide::default()
            })
            .expect("rope");
        assert_follows(&projected(&longer.nodes), &long, 6.0);
    }

    #[test]
    fn a_prior_sets_aside_what_the_rope_cannot_be() {
        let mut scene = Scene::new();
        scene.draw(&cable(), 2.5, 598);
        let truth = px_length(&cable()) * 0.6 / 615.0;
        let with = |prior| {
            scene.initialise(&InitGuide {
                prior,
                ..InitGuide::default()
            })
        };
        let right = with(RopePrior {
            length: Some(truth),
            diameter: Some(0.005),
        })
        .expect("the rope");
        let r = right.report.prior_length_ratio.expect("ratio");
        assert!((r - 1.0).abs() < 0.05, "{r}");
        // A 20 mm rope is not this 5 mm cable; a 0.3 m rope not this 0.5 m one.
        assert!(matches!(
            with(RopePrior {
                length: None,
                diameter: Some(0.02)
            }),
            Err(InitError::NothingRopeShaped {
                largest: SetAside {
                    reason: NotRope::Diameter { .. },
                    ..
                },
                ..
            })
        ));
        assert!(matches!(
            with(RopePrior {
                length: Some(0.3),
                diameter: None
            }),
            Err(InitError::NothingRopeShaped {
                largest: SetAside {
                    reason: NotRope::LongerThanPrior { .. },
                    ..
                },
                ..
            })
        ));
        assert!(RopePrior {
            length: Some(-1.0),
            diameter: None
        }
        .validate()
        .is_err());
        assert!(RopePrior {
            length: None,
            diameter: Some(f64::NAN)
        }
        .validate()
        .is_err());
    }
}
