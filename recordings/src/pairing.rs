//! Colour and depth frames paired by time: each colour frame with the depth
//! frame nearest in time, within half a frame period; a depth frame pairs
//! with at most one colour frame (the nearest). Frames left over are
//! counted and reported, never shifted onto a neighbour.

/// One colour frame and its depth frame, by index into each stream's list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FramePair {
    /// Index of the colour message.
    pub color: usize,
    /// Index of the depth message.
    pub depth: usize,
}

/// Pairs of a pairing, and what was left out.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Pairing {
    /// Pairs in colour order.
    pub pairs: Vec<FramePair>,
    /// Colour frames with no depth frame within half a period.
    pub unpaired_color: usize,
    /// Depth frames no colour frame was paired with.
    pub unpaired_depth: usize,
}

/// Pairs sorted colour and depth times (nanoseconds) within `tolerance_ns`.
pub fn pair_by_time(color: &[u64], depth: &[u64], tolerance_ns: u64) -> Pairing {
    // For each depth frame, the colour frame nearest to it that chose it.
    let mut best: Vec<Option<(u64, usize)>> = vec![None; depth.len()];
    for (ci, &t) in color.iter().enumerate() {
        let Some(di) = nearest(depth, t) else {
            continue;
        };
        let dt = t.abs_diff(depth[di]);
        if dt > tolerance_ns {
            continue;
        }
        if best[di].is_none_or(|(old, _)| dt < old) {
            best[di] = Some((dt, ci));
        }
    }
    let mut pairs: Vec<FramePair> = best
        .iter()
        .enumerate()
        .filter_map(|(di, b)| {
            b.map(|(_, ci)| FramePair {
                color: ci,
                depth: di,
            })
        })
        .collect();
    pairs.sort_by_key(|p| p.color);
    Pairing {
        unpaired_color: color.len() - pairs.len(),
        unpaired_depth: depth.len() - pairs.len(),
        pairs,
    }
}

/// Index of the value of sorted `times` nearest to `t`.
fn nearest(times: &[u64], t: u64) -> Option<usize> {
    let i = times.partition_point(|&x| x < t);
    let below = i.checked_sub(1);
    let above = (i < times.len()).then_some(i);
    match (below, above) {
        (Some(b), Some(a)) => Some(if t - times[b] <= times[a] - t { b } else { a }),
        (b, a) => b.or(a),
    }
}

/// Half the period of a stream at `fps` frames per second, nanoseconds.
pub fn half_period_ns(fps: f64) -> u64 {
    (0.5e9 / fps.max(1e-3)) as u64
}

/// A stream's frame rate from its message times: the median interval.
pub fn fps_from_times(times: &[u64]) -> Option<f64> {
    let mut d: Vec<u64> = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0)
        .collect();
    if d.is_empty() {
        return None;
    }
    d.sort_unstable();
    Some(1e9 / d[d.len() / 2] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn pairs_nearest_within_half_a_period() {
        let color = [0, 33 * MS, 66 * MS, 100 * MS];
        let depth = [MS, 34 * MS, 80 * MS + 1, 99 * MS];
        let p = pair_by_time(&color, &depth, 16 * MS);
        let got: Vec<(usize, usize)> = p.pairs.iter().map(|p| (p.color, p.depth)).collect();
        // 66 ms has its nearest depth 14 ms + 1 ns away: within; 80 ms depth taken by it.
        assert_eq!(got, vec![(0, 0), (1, 1), (2, 2), (3, 3)]);
        let strict = pair_by_time(&color, &depth, 14 * MS);
        assert_eq!(strict.pairs.len(), 3);
        assert_eq!((strict.unpaired_color, strict.unpaired_depth), (1, 1));
    }

    #[test]
    fn a_depth_frame_pairs_once_with_its_nearest_colour() {
        let color = [0, 10 * MS];
        let depth = [8 * MS];
        let p = pair_by_time(&color, &depth, 16 * MS);
        assert_eq!(p.pairs, vec![FramePair { color: 1, depth: 0 }]);
        assert_eq!(p.unpaired_color, 1);
    }

    #[test]
    fn frame_rate_is_the_median_interval() {
        let t = [0, 33 * MS, 66 * MS, 200 * MS, 233 * MS];
        let fps = fps_from_times(&t).expect("fps");
        assert!((fps - 1000.0 / 33.0).abs() < 1e-9);
        assert_eq!(fps_from_times(&[5]), None);
    }
}
