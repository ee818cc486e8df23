//! Evaluation of a result against ground truth: per-frame errors (Eq. 18)
//! in millimetres and pixels, and the summary statistics of a sequence.

use serde::Serialize;
use upetrack::curve::RopeCurve;
use upetrack::math::Vec3;
use upetrack::metrics::{frame_error, frame_error_px};
use upetrack::CameraIntrinsics;

use crate::result::TrackResult;

/// Frames above this error (millimetres) are counted as failures.
pub const FAILURE_THRESHOLD_MM: f64 = 20.0;

/// Error of one frame with ground truth.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct FrameError {
    /// Frame index.
    pub frame: usize,
    /// Frame error in millimetres.
    pub mm: f64,
    /// Frame error in pixels.
    pub px: f64,
}

/// Per-frame errors of `result`; frames without ground truth or nodes are skipped.
pub fn frame_errors(
    result: &TrackResult,
    truth: &[Option<Vec<Vec3>>],
    camera: &CameraIntrinsics,
) -> Vec<FrameError> {
    result
        .frames
        .iter()
        .filter_map(|f| {
            let gt = truth.get(f.frame)?.as_ref()?;
            let nodes: Vec<Vec3> = f
                .nodes
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect();
            let mm = frame_error(&nodes, gt)? * 1000.0;
            let px = frame_error_px(&nodes, gt, camera)?;
            Some(FrameError {
                frame: f.frame,
                mm,
                px,
            })
        })
        .collect()
}

/// Quantile `q` in `[0, 1]` of `values` by linear interpolation (NaN when empty).
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

/// Mean (NaN when empty).
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        f64::NAN
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

/// Mean, median and interquartile range of one error series.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct ErrorStats {
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// First quartile.
    pub q1: f64,
    /// Third quartile.
    pub q3: f64,
}

impl ErrorStats {
    /// Statistics of `values`.
    pub fn of(values: &[f64]) -> Self {
        Self {
            mean: mean(values),
            median: quantile(values, 0.5),
            q1: quantile(values, 0.25),
            q3: quantile(values, 0.75),
        }
    }
}

/// The summary of one sequence tracked by one algorithm.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Summary {
    /// Sequence name.
    pub sequence: String,
    /// Algorithm name.
    pub algorithm: String,
    /// Frames in the sequence.
    pub frames: usize,
    /// Frames reported lost.
    pub lost_frames: usize,
    /// Frames where the state contradicted the images and the rope was found again.
    pub recovered_frames: usize,
    /// Frames with ground truth and nodes.
    pub evaluated_frames: usize,
    /// Frame error in millimetres.
    pub mm: ErrorStats,
    /// Frame error in pixels.
    pub px: ErrorStats,
    /// Mean error (mm) over frames from the first occluded frame on.
    pub occluded_mean_mm: f64,
    /// Mean error (px) over frames from the first occluded frame on.
    pub occluded_mean_px: f64,
    /// Largest frame error, mm.
    pub max_mm: f64,
    /// Error of the last frame with ground truth, mm (TrackDLO's protocol).
    pub final_mm: f64,
    /// Frames above [`FAILURE_THRESHOLD_MM`].
    pub frames_above_20mm: usize,
    /// Median tracking step time, ms.
    pub median_track_ms: f64,
    /// Median whole-frame time, ms.
    pub median_total_ms: f64,
    /// Largest frame error in pixels.
    pub max_px: f64,
    /// Mean error (px) over the frames before the first occlusion.
    pub clear_mean_px: f64,
    /// Largest relative error of a hidden run's length against the true
    /// rope's length for as many node spacings, over all frames (0.05 = 5 %).
    pub hidden_length_error_max: f64,
    /// The same, averaged over the frames with a hidden run.
    pub hidden_length_error_mean: f64,
    /// Largest relative error of the whole tracked rope's length (its node
    /// polyline) against the true centre line's, over the frames tracked
    /// (0.03 = 3 %).
    pub length_error_max: f64,
    /// The same against the true centre line sampled at the tracker's node
    /// count by arc length (its polyline cuts the bends as the nodes' must):
    /// the part of [`Summary::length_error_max`] that is no chord of a
    /// bend.
    pub length_error_sampled_max: f64,
    /// Mean signed offset of the visible nodes from the true centre line
    /// along the viewing ray, millimetres (positive: behind it, farther
    /// from the camera), over every visible node of every frame tracked.
    pub visible_ray_offset_mm: f64,
    /// Mean distance, millimetres, from each end node the tracker saw to
    /// the true rope's end it stands for, over the frames tracked (NaN
    /// when no end was seen). Eq. 18 measures how far the nodes lie off
    /// the rope, not whether they reach its ends: an end node drawn in
    /// along the rope costs it nothing.
    pub end_mm: f64,
    /// The part of [`Summary::end_mm`] along the rope: the mean length of
    /// centre line, millimetres, from the true tip to the point nearest
    /// the end node (how far short of its tip the tracked rope stops).
    pub end_arc_mm: f64,
    /// The same distance as [`Summary::end_mm`] for the end nodes the
    /// tracker did not see: how near its estimate of a hidden end comes to
    /// the rope's tip (NaN when no end was hidden).
    pub hidden_end_mm: f64,
    /// With several ropes: how often a rope's nodes came to lie nearer
    /// another rope's ground truth than its own ([`identity_swaps`]); 0
    /// for one rope.
    pub identity_swaps: usize,
    /// With several ropes: frames where some rope's nodes lie nearer
    /// another rope's ground truth than its own.
    pub swapped_frames: usize,
}

/// How well several ropes kept their identities.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct IdentitySwaps {
    /// Times a frame with a rope nearer another's ground truth than its
    /// own followed one without.
    pub swaps: usize,
    /// Frames with a rope nearer another's ground truth than its own.
    pub swapped_frames: usize,
}

/// Counts identity swaps among `tracks` (each rope's result and ground
/// truth): a frame is swapped when some rope's nodes have a smaller frame
/// error (Eq. 18) against another rope's ground truth than against its own.
pub fn identity_swaps(tracks: &[Track<'_>]) -> IdentitySwaps {
    let frames = tracks
        .iter()
        .map(|t| t.result.frames.len())
        .max()
        .unwrap_or(0);
    let nodes_of = |t: &Track<'_>, f: usize| -> Option<Vec<Vec3>> {
        let record = t.result.frames.get(f)?;
        (!record.lost && !record.nodes.is_empty()).then(|| {
            record
                .nodes
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect()
        })
    };
    let mut out = IdentitySwaps::default();
    let mut was = false;
    for f in 0..frames {
        let swapped = tracks.iter().enumerate().any(|(k, t)| {
            let Some(nodes) = nodes_of(t, f) else {
                return false;
            };
            let error = |u: &Track<'_>| {
                let gt = u.truth.get(f)?.as_ref()?;
                frame_error(&nodes, gt)
            };
            let Some(own) = error(t) else {
                return false;
            };
            tracks
                .iter()
                .enumerate()
                .any(|(j, u)| j != k && error(u).is_some_and(|e| e < own))
        });
        if swapped {
            out.swapped_frames += 1;
            if !was {
                out.swaps += 1;
            }
        }
        was = swapped;
    }
    out
}

/// The signed offset of `p` from its nearest point `q` on the polyline
/// `line` along the viewing ray through `q` (camera at the origin),
/// metres; positive when `p` lies behind `q`.
pub fn ray_offset(p: &Vec3, line: &[Vec3]) -> Option<f64> {
    let q = line
        .windows(2)
        .map(|w| {
            let t = upetrack::math::nearest_on_segment(p, &w[0], &w[1]);
            w[0] + (w[1] - w[0]) * t
        })
        .min_by(|a, b| (a - p).norm_squared().total_cmp(&(b - p).norm_squared()))?;
    let n = q.norm();
    (n > 0.0).then(|| (p - q).dot(&(q / n)))
}

/// The relative length error of the worst hidden run of one frame: each
/// maximal run of hidden nodes, with the visible node on each side, against
/// `segments x L / (M - 1)` where `L` is the true rope length. `None` when
/// no node is hidden (or there is nothing to compare).
pub fn hidden_length_error(nodes: &[Vec3], visible: &[bool], true_length: f64) -> Option<f64> {
    let m = nodes.len();
    if m < 2 || visible.len() != m || !(true_length > 0.0) || visible.iter().all(|&v| !v) {
        return None;
    }
    let spacing = true_length / (m - 1) as f64;
    let mut worst: Option<f64> = None;
    let mut i = 0;
    while i < m {
        if visible[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < m && !visible[i] {
            i += 1;
        }
        // Nodes start..i are hidden; include the visible neighbours.
        let (a, b) = (start.saturating_sub(1), i.min(m - 1));
        if b <= a {
            continue;
        }
        let length: f64 = (a..b).map(|k| (nodes[k + 1] - nodes[k]).norm()).sum();
        let expected = (b - a) as f64 * spacing;
        let e = (length - expected).abs() / expected;
        worst = Some(worst.map_or(e, |w| w.max(e)));
    }
    worst
}

/// Where an end node stands against the true rope's end: its distance
/// from the tip and the length of centre line from the tip to the point
/// nearest it, metres ([`end_offsets`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndOffset {
    /// Distance from the node to the true tip.
    pub distance: f64,
    /// Centre line from the tip to the node's nearest point on it.
    pub arc: f64,
}

/// The offsets of the end nodes marked in `measured` from the true rope's
/// ends (the polyline `truth`), the node polyline's ends paired with the
/// true ones the way that puts them nearer in all. Empty when either has
/// fewer than two points.
pub fn end_offsets(nodes: &[Vec3], measured: &[bool], truth: &[Vec3]) -> Vec<EndOffset> {
    let (m, n) = (nodes.len(), truth.len());
    if m < 2 || n < 2 || measured.len() != m {
        return Vec::new();
    }
    let (first, last) = (nodes[0], nodes[m - 1]);
    let forward = (first - truth[0]).norm() + (last - truth[n - 1]).norm();
    let reversed = (first - truth[n - 1]).norm() + (last - truth[0]).norm();
    // The true tip node 0 stands for is the start of `truth`, or its end.
    let head_at_start = !(reversed < forward);
    let curve = RopeCurve::polyline(truth);
    // Centre line between the tip at `truth`'s start (or end) and `p`'s
    // nearest point.
    let arc = |p: &Vec3, from_start: bool| {
        let s = curve.project(p, 0.0, f64::INFINITY);
        if from_start {
            s
        } else {
            curve.length() - s
        }
    };
    let tip = |at_start: bool| if at_start { truth[0] } else { truth[n - 1] };
    let mut out = Vec::new();
    for (node, at_start, wanted) in [
        (first, head_at_start, measured[0]),
        (last, !head_at_start, measured[m - 1]),
    ] {
        if wanted {
            out.push(EndOffset {
                distance: (node - tip(at_start)).norm(),
                arc: arc(&node, at_start),
            });
        }
    }
    out
}

/// Summarises `result` against `truth`.
pub fn summarise(
    sequence: &str,
    result: &TrackResult,
    truth: &[Option<Vec<Vec3>>],
    camera: &CameraIntrinsics,
    first_occluded: Option<usize>,
) -> Summary {
    summarise_tracks(
        sequence,
        &[Track {
            result,
            truth,
            first_occluded,
        }],
        camera,
    )
}

/// One rope's result with its ground truth, for [`summarise_tracks`].
#[derive(Debug, Clone, Copy)]
pub struct Track<'a> {
    /// The rope's frames.
    pub result: &'a TrackResult,
    /// Its ground truth per frame index.
    pub truth: &'a [Option<Vec<Vec3>>],
    /// The first frame part of it is hidden.
    pub first_occluded: Option<usize>,
}

/// Summarises several ropes' results as one: every statistic over the
/// frames of all of them (a frame of two ropes counts twice), the frame
/// count and the times the first's.
pub fn summarise_tracks(
    sequence: &str,
    tracks: &[Track<'_>],
    camera: &CameraIntrinsics,
) -> Summary {
    let (mut mm, mut px, mut occ_mm, mut occ_px, mut clear) =
        (vec![], vec![], vec![], vec![], vec![]);
    let (mut length_errors, mut whole_length_errors, mut ray_offsets) = (vec![], vec![], vec![]);
    let mut sampled_length_errors = vec![];
    let (mut ends, mut hidden_ends): (Vec<EndOffset>, Vec<EndOffset>) = (vec![], vec![]);
    let (mut lost, mut recovered, mut last_mm) = (0, 0, f64::NAN);
    for t in tracks {
        let errs = frame_errors(t.result, t.truth, camera);
        mm.extend(errs.iter().map(|e| e.mm));
        px.extend(errs.iter().map(|e| e.px));
        last_mm = errs.last().map_or(last_mm, |e| e.mm);
        if let Some(f) = t.first_occluded {
            occ_mm.extend(errs.iter().filter(|e| e.frame >= f).map(|e| e.mm));
            occ_px.extend(errs.iter().filter(|e| e.frame >= f).map(|e| e.px));
            clear.extend(errs.iter().filter(|e| e.frame < f).map(|e| e.px));
        } else {
            clear.extend(errs.iter().map(|e| e.px));
        }
        lost += t.result.frames.iter().filter(|f| f.lost).count();
        recovered += t.result.frames.iter().filter(|f| f.recovered).count();
        // The hidden runs' and the whole rope's length, and the visible
        // nodes' offset along the ray.
        for f in t.result.frames.iter().filter(|f| !f.lost) {
            let Some(gt) = t.truth.get(f.frame).and_then(|t| t.as_ref()) else {
                continue;
            };
            let nodes: Vec<Vec3> = f
                .nodes
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect();
            let true_length = upetrack::polyline::polyline_length(gt);
            length_errors.extend(hidden_length_error(&nodes, &f.visible, true_length));
            if true_length > 0.0 && nodes.len() > 1 {
                let length = upetrack::polyline::polyline_length(&nodes);
                whole_length_errors.push((length / true_length - 1.0).abs());
                let sampled = upetrack::polyline::polyline_length(
                    &upetrack::polyline::resample_uniform(gt, nodes.len()),
                );
                if sampled > 0.0 {
                    sampled_length_errors.push((length / sampled - 1.0).abs());
                }
            }
            for (p, _) in nodes.iter().zip(&f.visible).filter(|(_, v)| **v) {
                ray_offsets.extend(ray_offset(p, gt).map(|o| o * 1000.0));
            }
            ends.extend(end_offsets(&nodes, &f.visible, gt));
            let hidden: Vec<bool> = f.visible.iter().map(|v| !v).collect();
            hidden_ends.extend(end_offsets(&nodes, &hidden, gt));
        }
    }
    let first = tracks.first().map(|t| t.result);
    let frames = first.map_or(&[][..], |r| r.frames.as_slice());
    let track: Vec<f64> = frames.iter().map(|f| f.track_ms).collect();
    let total: Vec<f64> = frames.iter().map(|f| f.total_ms).collect();
    let largest = |v: &[f64]| v.iter().copied().fold(f64::NAN, f64::max);
    Summary {
        sequence: sequence.to_string(),
        algorithm: first.map_or(String::new(), |r| r.algorithm.clone()),
        frames: frames.len(),
        lost_frames: lost,
        recovered_frames: recovered,
        evaluated_frames: mm.len(),
        mm: ErrorStats::of(&mm),
        px: ErrorStats::of(&px),
        occluded_mean_mm: mean(&occ_mm),
        occluded_mean_px: mean(&occ_px),
        max_mm: largest(&mm),
        final_mm: last_mm,
        frames_above_20mm: mm.iter().filter(|&&e| e > FAILURE_THRESHOLD_MM).count(),
        median_track_ms: quantile(&track, 0.5),
        median_total_ms: quantile(&total, 0.5),
        max_px: largest(&px),
        clear_mean_px: mean(&clear),
        hidden_length_error_max: largest(&length_errors),
        hidden_length_error_mean: mean(&length_errors),
        length_error_max: largest(&whole_length_errors),
        length_error_sampled_max: largest(&sampled_length_errors),
        visible_ray_offset_mm: mean(&ray_offsets),
        end_mm: 1000.0 * mean(&ends.iter().map(|e| e.distance).collect::<Vec<_>>()),
        end_arc_mm: 1000.0 * mean(&ends.iter().map(|e| e.arc).collect::<Vec<_>>()),
        hidden_end_mm: 1000.0 * mean(&hidden_ends.iter().map(|e| e.distance).collect::<Vec<_>>()),
        identity_swaps: 0,
        swapped_frames: 0,
    }
}

/// The rows of a result of several ropes: one per rope (`<sequence>/<rope
/// name>`) and one of all of them (`<sequence>/all`, with the identity
/// swaps); of one rope, its one row.
pub fn summarise_ropes<S: crate::source::Source>(
    sequence: &str,
    result: &TrackResult,
    seq: &crate::sequence::Sequence<S>,
) -> Vec<Summary> {
    let (ropes, camera) = (&seq.ropes, &seq.camera);
    let results: Vec<TrackResult> = (0..result.rope_count())
        .filter_map(|k| result.rope(k))
        .collect();
    let tracks: Vec<Track<'_>> = results
        .iter()
        .zip(ropes.iter().enumerate())
        .map(|(r, (k, rope))| Track {
            result: r,
            truth: &rope.groundtruth,
            first_occluded: seq.first_occluded_frame_of(k),
        })
        .collect();
    if result.ropes.is_empty() {
        return tracks
            .first()
            .map(|t| summarise(sequence, t.result, t.truth, camera, t.first_occluded))
            .into_iter()
            .collect();
    }
    let mut rows: Vec<Summary> = tracks
        .iter()
        .zip(ropes)
        .map(|(t, rope)| summarise_tracks(&format!("{sequence}/{}", rope.name), &[*t], camera))
        .collect();
    let mut all = summarise_tracks(&format!("{sequence}/all"), &tracks, camera);
    let swaps = identity_swaps(&tracks);
    all.identity_swaps = swaps.swaps;
    all.swapped_frames = swaps.swapped_frames;
    rows.push(all);
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ray_offset_is_signed_along_the_line_of_sight() {
        // A line across the view 0.5 m ahead; a point 2 mm behind it and
        // 3 mm beside it along the line.
        let line = [Vec3::new(-0.1, 0.0, 0.5), Vec3::new(0.1, 0.0, 0.5)];
        let behind = ray_offset(&Vec3::new(0.003, 0.0, 0.502), &line).expect("offset");
        assert!((behind - 0.002).abs() < 1e-4, "{behind}");
        let before = ray_offset(&Vec3::new(0.0, 0.001, 0.497), &line).expect("offset");
        assert!((before + 0.003).abs() < 1e-4, "{before}");
        assert_eq!(ray_offset(&Vec3::zeros(), &line[..1]), None);
    }

    #[test]
    fn hidden_runs_are_measured_with_their_visible_neighbours() {
        // Ten nodes 1 cm apart on a line; the true rope is 9 cm long.
        let mut nodes: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.5))
            .collect();
        let mut visible = vec![true; 10];
        assert_eq!(hidden_length_error(&nodes, &visible, 0.09), None);
        // A middle run 4-5 stretched: node 5 moved 1 cm out of line.
        visible[4] = false;
        visible[5] = false;
        nodes[5].y = 0.01;
        let e = hidden_length_error(&nodes, &visible, 0.09).expect("a run");
        // Segments 3-4, 4-5, 5-6: 1 + sqrt(2) + sqrt(2) cm against 3 cm.
        let expected = (1.0 + 2.0 * 2f64.sqrt() - 3.0) / 3.0;
        assert!((e - expected).abs() < 1e-12, "{e} vs {expected}");
        // A hidden tail of two nodes at their spacing: no error there.
        let mut visible = vec![true; 10];
        visible[8] = false;
        visible[9] = false;
        let line: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.5))
            .collect();
        assert!(hidden_length_error(&line, &visible, 0.09).expect("tail") < 1e-12);
        assert_eq!(hidden_length_error(&line, &[false; 10], 0.09), None);
    }

    /// Regression for "an end node drawn in along the rope costs Eq. 18
    /// nothing": the end offsets see it, in either node order.
    #[test]
    fn end_nodes_short_of_the_tips_are_measured_along_the_rope() {
        // A true rope 1 m along x; nodes from 5 cm in to 3 cm past the far tip.
        let truth: Vec<Vec3> = (0..=10)
            .map(|k| Vec3::new(0.1 * k as f64, 0.0, 0.6))
            .collect();
        let nodes: Vec<Vec3> = (0..=10)
            .map(|k| Vec3::new(0.05 + 0.098 * k as f64, 0.0, 0.6))
            .collect();
        let both = end_offsets(&nodes, &[true; 11], &truth);
        assert_eq!(both.len(), 2);
        assert!((both[0].distance - 0.05).abs() < 1e-12 && (both[0].arc - 0.05).abs() < 1e-12);
        // Past the tip: as far from it, and no centre line short of it.
        assert!((both[1].distance - 0.03).abs() < 1e-12 && both[1].arc.abs() < 1e-12);
        let reversed: Vec<Vec3> = nodes.iter().rev().copied().collect();
        let again = end_offsets(&reversed, &[true; 11], &truth);
        assert!((again[0].distance - 0.03).abs() < 1e-12 && (again[1].arc - 0.05).abs() < 1e-12);
        // Only the ends asked for are measured (a summary asks for the
        // seen ones and, apart, the hidden ones); too few points, nothing.
        let mut visible = [true; 11];
        visible[0] = false;
        assert_eq!(end_offsets(&nodes, &visible, &truth).len(), 1);
        let hidden: Vec<bool> = visible.iter().map(|v| !v).collect();
        let head = end_offsets(&nodes, &hidden, &truth);
        assert!(head.len() == 1 && (head[0].distance - 0.05).abs() < 1e-12);
        assert!(end_offsets(&nodes[..1], &[true], &truth).is_empty());
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [4.0, 1.0, 3.0, 2.0];
        assert_eq!(quantile(&v, 0.5), 2.5);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&v, 1.0), 4.0);
        assert_eq!(quantile(&v, 0.25), 1.75);
        assert!(quantile(&[], 0.5).is_nan());
        assert_eq!(mean(&v), 2.5);
    }
}
