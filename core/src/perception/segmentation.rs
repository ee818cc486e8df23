//! Colour segmentation: HSV thresholds in OpenCV's 8-bit convention
//! (H 0..179, S and V 0..255), applied after the occlusion rectangles are
//! blacked out, as the UPETrack and TrackDLO evaluations do.

use alloc::vec;
use alloc::vec::Vec;

use super::frame::Frame;

/// Largest hue value in OpenCV's 8-bit convention.
pub const HUE_MAX: u8 = 179;

/// Hue half-width of the range picked around a clicked colour (OpenCV
/// units, 2 degrees each): 12 covers a rope's shading on a D435i image.
pub const PICK_HUE_HALF_WIDTH: u8 = 12;
/// How far below the clicked saturation the picked range reaches.
pub const PICK_SATURATION_BELOW: u8 = 70;
/// How far below the clicked value the picked range reaches (shadows).
pub const PICK_VALUE_BELOW: u8 = 90;
/// Lowest saturation a picked coloured range starts at: greys never pass.
pub const PICK_MIN_SATURATION: u8 = 40;
/// Lowest value a picked coloured range starts at: black never passes.
pub const PICK_MIN_VALUE: u8 = 20;
/// A clicked pixel darker than this (value) is black: its hue and
/// saturation are the camera's noise (a channel of 10 +- 3 swings the
/// saturation over the whole range), so the range takes any hue and any
/// saturation up to a value a little above the pixel's.
pub const PICK_DARK_VALUE: u8 = 64;
/// How far above the clicked value a black range reaches (highlights).
pub const PICK_DARK_VALUE_ABOVE: u8 = 48;
/// A clicked pixel less saturated than this is grey or white: any hue and
/// saturation, chroma up to a margin above the pixel's.
pub const PICK_GREY_SATURATION: u8 = 40;
/// The colour noise a grey range allows for ([`HsvRange::chroma_noise`]),
/// 8-bit levels of chroma: the camera's noise on each channel and the
/// JPEG's subsampled chroma on a grey surface, whatever its brightness.
/// Its saturation bound is then the clicked pixel's own: a bright table a
/// little more saturated than the rope stays out, and the rope's shaded
/// side, where the same noise is a large saturation, comes in.
pub const PICK_GREY_CHROMA_NOISE: u8 = 20;
/// The share of the clicked value a grey or white rope's shaded side keeps,
/// in 1/256: light falls on a round rope's flank at a grazing angle, so
/// the flank is a fraction of the lit top's brightness, not a fixed number
/// of levels below it.
pub const PICK_SHADED_SHARE_256: u16 = 128;

/// The lowest value a grey or white range takes for a click of value `v`:
/// [`PICK_SHADED_SHARE_256`] of it.
fn shaded_value(v: u8) -> u8 {
    ((u16::from(v) * PICK_SHADED_SHARE_256 + 128) >> 8) as u8
}

/// Errors in segmentation settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SegmentationError {
    /// A hue bound is above [`HUE_MAX`].
    #[error("hue bound {value} is out of range (OpenCV hue is 0..=179)")]
    HueOutOfRange {
        /// The rejected hue.
        value: u8,
    },
    /// A saturation or value lower bound is above its upper bound.
    #[error("{channel} range is inverted: lower {lower} > upper {upper}")]
    InvertedRange {
        /// `saturation` or `value`.
        channel: &'static str,
        /// Lower bound.
        lower: u8,
        /// Upper bound.
        upper: u8,
    },
}

/// An inclusive HSV box. A lower hue above the upper hue wraps through 0
/// (for red ropes); saturation and value never wrap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HsvRange {
    /// `[h, s, v]` lower bounds.
    pub lower: [u8; 3],
    /// `[h, s, v]` upper bounds.
    pub upper: [u8; 3],
    /// The camera's colour noise allowed for when the saturation is
    /// tested, in 8-bit levels of chroma (`max(R, G, B) - min(R, G, B)`): a
    /// pixel passes the saturation bounds when a chroma within this many
    /// levels of its own would. 0 (the default) is OpenCV's `inRange`
    /// exactly. Saturation is `255 chroma / max`: on the dark, shaded side
    /// of a grey rope a few levels of noise are a large saturation, on its
    /// lit side and on a bright table they are not. `dlo.json`:
    /// `segmentation.chroma_noise`, absent when 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub chroma_noise: u8,
}

impl Default for HsvRange {
    /// TrackDLO's thresholds for a blue rope: lower (90, 90, 30), upper (130, 255, 255).
    fn default() -> Self {
        Self::new([90, 90, 30], [130, 255, 255])
    }
}

impl HsvRange {
    /// OpenCV's box from `lower` to `upper` (`[h, s, v]`), no colour noise
    /// allowed for.
    pub const fn new(lower: [u8; 3], upper: [u8; 3]) -> Self {
        Self {
            lower,
            upper,
            chroma_noise: 0,
        }
    }

    /// Checks the bounds (hue in range, S and V not inverted).
    pub fn validate(&self) -> Result<(), SegmentationError> {
        for h in [self.lower[0], self.upper[0]] {
            if h > HUE_MAX {
                return Err(SegmentationError::HueOutOfRange { value: h });
            }
        }
        for (i, channel) in [(1, "saturation"), (2, "value")] {
            if self.lower[i] > self.upper[i] {
                return Err(SegmentationError::InvertedRange {
                    channel,
                    lower: self.lower[i],
                    upper: self.upper[i],
                });
            }
        }
        Ok(())
    }

    /// `true` for a colour without a hue worth trusting: black (value
    /// below [`PICK_DARK_VALUE`]) or grey and white (saturation below
    /// [`PICK_GREY_SATURATION`]).
    pub fn is_achromatic(hsv: [u8; 3]) -> bool {
        hsv[2] < PICK_DARK_VALUE || hsv[1] < PICK_GREY_SATURATION
    }

    /// The range picked around one clicked pixel's colour. A coloured
    /// pixel: its hue `+-PICK_HUE_HALF_WIDTH` (wrapping through 0),
    /// saturation and value from a margin below the pixel's up to 255,
    /// never down to grey or black. A black pixel: any hue and saturation,
    /// value up to [`PICK_DARK_VALUE_ABOVE`] above its own. A grey or white
    /// one: any hue, saturation up to its own with
    /// [`PICK_GREY_CHROMA_NOISE`] levels of colour noise allowed for
    /// ([`HsvRange::chroma_noise`]), value from [`PICK_SHADED_SHARE_256`]
    /// of its own.
    pub fn around(rgb: [u8; 3]) -> Self {
        let [h, s, v] = rgb_to_hsv(rgb);
        if v < PICK_DARK_VALUE {
            return Self::new(
                [0, 0, 0],
                [HUE_MAX, 255, v.saturating_add(PICK_DARK_VALUE_ABOVE)],
            );
        }
        if s < PICK_GREY_SATURATION {
            return Self {
                lower: [0, 0, shaded_value(v)],
                upper: [HUE_MAX, s, 255],
                chroma_noise: PICK_GREY_CHROMA_NOISE,
            };
        }
        let hues = u16::from(HUE_MAX) + 1;
        let lower_h = (u16::from(h) + hues - u16::from(PICK_HUE_HALF_WIDTH)) % hues;
        let upper_h = (u16::from(h) + u16::from(PICK_HUE_HALF_WIDTH)) % hues;
        Self::new(
            [
                lower_h as u8,
                s.saturating_sub(PICK_SATURATION_BELOW)
                    .max(PICK_MIN_SATURATION),
                v.saturating_sub(PICK_VALUE_BELOW).max(PICK_MIN_VALUE),
            ],
            [upper_h as u8, 255, 255],
        )
    }

    /// `true` when the HSV triple lies in the box.
    #[inline]
    pub fn contains(&self, hsv: [u8; 3]) -> bool {
        let [h, s, v] = hsv;
        let hue_ok = if self.lower[0] <= self.upper[0] {
            h >= self.lower[0] && h <= self.upper[0]
        } else {
            h >= self.lower[0] || h <= self.upper[0]
        };
        hue_ok
            && s >= self.lower[1]
            && s <= self.upper[1]
            && v >= self.lower[2]
            && v <= self.upper[2]
    }

    /// `true` when an RGB pixel passes: its HSV in the box
    /// ([`HsvRange::contains`]), its saturation allowed
    /// [`HsvRange::chroma_noise`] levels of chroma either way. [`segment`]
    /// takes exactly these pixels.
    pub fn contains_rgb(&self, rgb: [u8; 3]) -> bool {
        let [h, _, v] = rgb_to_hsv(rgb);
        let (hi, lo) = (
            rgb[0].max(rgb[1]).max(rgb[2]),
            rgb[0].min(rgb[1]).min(rgb[2]),
        );
        let (v, diff) = (i32::from(v), i32::from(hi - lo));
        let noise = i32::from(self.chroma_noise);
        ((diff - noise).max(0)..=(diff + noise).min(v)).any(|d| {
            let s = saturation(v, d) as u8;
            self.contains([h, s, v as u8])
        })
    }
}

/// An axis-aligned rectangle in pixels (x, y of the top-left corner, width, height).
/// It may reach outside the image; only the part inside is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Rect {
    /// Left edge, pixels.
    pub x: i64,
    /// Top edge, pixels.
    pub y: i64,
    /// Width, pixels.
    pub w: i64,
    /// Height, pixels.
    pub h: i64,
}

impl Rect {
    /// The part of the rectangle inside a `width` x `height` image, as
    /// half-open pixel ranges `(x0, x1, y0, y1)`, or `None` if empty.
    pub fn clip(&self, width: u32, height: u32) -> Option<(usize, usize, usize, usize)> {
        let x0 = self.x.max(0);
        let y0 = self.y.max(0);
        let x1 = self.x.saturating_add(self.w.max(0)).min(width as i64);
        let y1 = self.y.saturating_add(self.h.max(0)).min(height as i64);
        if x0 >= x1 || y0 >= y1 {
            return None;
        }
        Some((x0 as usize, x1 as usize, y0 as usize, y1 as usize))
    }

    /// `true` when pixel `(u, v)` is inside.
    pub fn contains(&self, u: i64, v: i64) -> bool {
        u >= self.x
            && v >= self.y
            && u < self.x.saturating_add(self.w)
            && v < self.y.saturating_add(self.h)
    }
}

/// A binary image: `true` where the rope was segmented.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major, one entry per pixel.
    pub data: Vec<bool>,
}

impl Mask {
    /// An all-false mask.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![false; width as usize * height as usize],
        }
    }

    /// The value at `(u, v)`, `false` outside the image.
    #[inline]
    pub fn get(&self, u: i64, v: i64) -> bool {
        if u < 0 || v < 0 || u >= self.width as i64 || v >= self.height as i64 {
            return false;
        }
        self.data[v as usize * self.width as usize + u as usize]
    }

    /// Number of set pixels.
    pub fn count(&self) -> usize {
        self.data.iter().filter(|&&b| b).count()
    }

    /// Sets every pixel `other` sets (a mask of another size adds nothing).
    pub fn include(&mut self, other: &Mask) {
        if (other.width, other.height) == (self.width, self.height) {
            self.data
                .iter_mut()
                .zip(&other.data)
                .for_each(|(p, &o)| *p |= o);
        }
    }
}

/// `round((255 << 12) / v)`, OpenCV's saturation divisor table.
const fn saturation_divisors() -> [i32; 256] {
    let mut t = [0i32; 256];
    let mut i = 1;
    while i < 256 {
        t[i] = ((255 << 12) + i as i32 / 2) / i as i32;
        i += 1;
    }
    t
}

/// `round((180 << 12) / (6 d))`, OpenCV's hue divisor table for 8-bit hue.
const fn hue_divisors() -> [i32; 256] {
    let mut t = [0i32; 256];
    let mut i = 1;
    while i < 256 {
        let den = 6 * i as i32;
        t[i] = ((180 << 12) + den / 2) / den;
        i += 1;
    }
    t
}

static SDIV: [i32; 256] = saturation_divisors();
static HDIV: [i32; 256] = hue_divisors();

/// OpenCV's 8-bit hue from the channels, `v = max` and `diff = max - min`.
#[inline]
fn hue(r: i32, g: i32, b: i32, v: i32, diff: i32) -> i32 {
    let h_raw = if diff == 0 {
        0
    } else if v == r {
        g - b
    } else if v == g {
        b - r + 2 * diff
    } else {
        r - g + 4 * diff
    };
    let mut h = (h_raw * HDIV[diff as usize] + (1 << 11)) >> 12;
    if h < 0 {
        h += 180;
    }
    if h >= 180 {
        h -= 180;
    }
    h
}

/// OpenCV's 8-bit saturation from `v = max` and `diff = max - min`.
#[inline]
fn saturation(v: i32, diff: i32) -> i32 {
    (diff * SDIV[v as usize] + (1 << 11)) >> 12
}

/// RGB to HSV as OpenCV's `cvtColor(..., COLOR_RGB2HSV)` does for 8-bit
/// images: H in 0..=179, S and V in 0..=255 (fixed-point, same rounding).
#[inline]
pub fn rgb_to_hsv(rgb: [u8; 3]) -> [u8; 3] {
    let (r, g, b) = (rgb[0] as i32, rgb[1] as i32, rgb[2] as i32);
    let v = r.max(g).max(b);
    let diff = v - r.min(g).min(b);
    [
        hue(r, g, b, v, diff) as u8,
        saturation(v, diff) as u8,
        v as u8,
    ]
}

/// Pixels tested together by the vectorised pre-test of [`segment`].
const SEGMENT_BLOCK: usize = 32;

/// Where the first pre-test of [`segment`] passed more than three in four
/// blocks of the last window of [`PRETEST_WINDOW`] blocks, it runs on one
/// block in this many of the next (a speed setting only: the mask is the
/// same whatever it is; on 15 hand-made and drawn sequences it took 10-25 %
/// off the segmentation where a table passes that pre-test, and added up to
/// 5 % elsewhere).
const FIRST_PRETEST_PERIOD: usize = 8;
/// Blocks over which the first pre-test's passes are counted.
const PRETEST_WINDOW: usize = 32;

/// 1 at the bytes of a block of RGB8 pixels where a pixel starts.
const PIXEL_STARTS: [u8; 3 * SEGMENT_BLOCK] = {
    let mut t = [0u8; 3 * SEGMENT_BLOCK];
    let mut i = 0;
    while i < SEGMENT_BLOCK {
        t[3 * i] = 1;
        i += 1;
    }
    t
};

/// For each value `v` (the largest channel), the chroma `diff = max - min`
/// whose saturation falls in `range` form one interval (saturation grows
/// with `diff` at a fixed `v`): `(first, count)`, `count = 0` where `v` is
/// outside the value range. A pixel then passes both tests when
/// `diff - first < count` as unsigned numbers. The interval is widened by
/// [`HsvRange::chroma_noise`] on each side.
fn chroma_intervals(range: &HsvRange) -> [(i32, u32); 256] {
    let (v_lo, v_hi) = (range.lower[2] as i32, range.upper[2] as i32);
    let (s_lo, s_hi) = (range.lower[1] as i32, range.upper[1] as i32);
    let mut table = [(0, 0); 256];
    for (v, slot) in table.iter_mut().enumerate() {
        let v = v as i32;
        if v < v_lo || v > v_hi {
            continue;
        }
        // The first diff in 0..=v whose saturation is at least `s`
        // (v + 1 when none is), by bisection on the monotone saturation.
        let first_reaching = |s: i32| {
            let (mut lo, mut hi) = (0, v + 1);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if saturation(v, mid) >= s {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            lo
        };
        let first = first_reaching(s_lo);
        let end = first_reaching(s_hi + 1);
        if end > first {
            let noise = i32::from(range.chroma_noise);
            let (first, end) = ((first - noise).max(0), (end + noise).min(v + 1));
            *slot = (first, (end - first) as u32);
        }
    }
    table
}

/// Hue units of one sixth of the hue circle: within each, the same channel
/// is largest and the same smallest.
const HUE_SECTOR: i32 = (HUE_MAX as i32 + 1) / 6;

/// Which sixths of the hue circle the hue range meets, one unit wider on
/// each side (OpenCV's fixed-point hue is within a unit of the true hue),
/// as 0 or 1 per sixth, for a pre-test on bytes. Sixth `k` holds the hues
/// `k * 60 .. (k + 1) * 60` degrees; a pixel is in it when its channels
/// are ordered as [`in_hue_sectors`] says (ties in both neighbours).
fn hue_sectors(range: &HsvRange) -> [u8; 6] {
    let circle = HUE_MAX as i32 + 1;
    let start = i32::from(range.lower[0]) - 1;
    let length = (i32::from(range.upper[0]) - i32::from(range.lower[0])).rem_euclid(circle) + 2;
    let mut met = [0u8; 6];
    for (k, m) in met.iter_mut().enumerate() {
        // The sixth [a, a + 60) meets the arc [start, start + length] when
        // the arc's start lies within `length` before the sixth's end.
        let a = k as i32 * HUE_SECTOR;
        let before_end = (a + HUE_SECTOR - start).rem_euclid(circle);
        let from_start = (a - start).rem_euclid(circle);
        *m = u8::from(length + 1 >= circle || from_start <= length || before_end <= HUE_SECTOR);
    }
    met
}

/// 1 when a pixel's channels put it in a sixth of the hue circle marked
/// in `sectors` (a grey pixel is in all of them), else 0. Byte
/// comparisons only, so that lanes of pixels vectorise.
#[inline(always)]
fn in_hue_sectors(sectors: &[u8; 6], r: u8, g: u8, b: u8) -> u8 {
    let (rg, gr) = (u8::from(r >= g), u8::from(g >= r));
    let (gb, bg) = (u8::from(g >= b), u8::from(b >= g));
    let (rb, br) = (u8::from(r >= b), u8::from(b >= r));
    (sectors[0] & rg & gb)
        | (sectors[1] & gr & rb)
        | (sectors[2] & gb & br)
        | (sectors[3] & bg & gr)
        | (sectors[4] & br & rg)
        | (sectors[5] & rb & bg)
}

/// The second pre-test of [`segment`] on a block's channel lanes: `false`
/// only when no pixel's saturation can reach `s_lo` or (with `UPPER`,
/// for a range that stops below 255) stay below `s_hi_next`, with its
/// chroma moved by up to `noise` levels ([`HsvRange::chroma_noise`]) the
/// way that helps it.
#[inline(always)]
fn may_be_saturated<const UPPER: bool>(
    [r, g, b]: [&[u8; 3 * SEGMENT_BLOCK]; 3],
    s_lo: u16,
    s_hi_next: u16,
    noise: u8,
) -> bool {
    let mut saturated = 0u8;
    for i in 0..3 * SEGMENT_BLOCK {
        let (hi, lo) = (r[i].max(g[i]).max(b[i]), r[i].min(g[i]).min(b[i]));
        let diff = hi - lo;
        let (more, less) = (
            diff.saturating_add(noise).min(hi),
            diff.saturating_sub(noise),
        );
        let (v, more, less) = (u16::from(hi), u16::from(more), u16::from(less));
        let within = 255 * more + v >= s_lo * v && (!UPPER || 255 * less <= s_hi_next * v);
        saturated |= PIXEL_STARTS[i] & u8::from(within);
    }
    saturated != 0
}

/// Segments `frame` with `range` after setting the colour pixels inside each
/// of `occlusions` to black (depth is left as it is). Value and saturation
/// are tested together by one table lookup per pixel (`chroma_intervals`),
/// so hue is computed only for candidate pixels.
///
/// With `std` on x86-64, the same code compiled for AVX-512 or AVX2 runs
/// where the processor has them (`wide`): the pre-tests are byte and
/// 16-bit integer lanes, so the mask is the same bit for bit, two to four
/// times as many lanes at once.
pub fn segment(frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Mask {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if let Some(mask) = wide::segment(frame, range, occlusions) {
        return mask;
    }
    segment_portable(frame, range, occlusions)
}

/// Which variant [`segment`] runs on this processor: `"AVX-512"`, `"AVX2"`
/// or `"portable"` (every variant gives the same mask; only its speed
/// differs, so a benchmark names it).
pub fn segmentation_variant() -> &'static str {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if let Some(name) = wide::name() {
        return name;
    }
    "portable"
}

/// [`segment`] with the instructions every target has (what wasm runs).
#[inline(always)]
fn segment_portable(frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Mask {
    let mut mask = Mask::new(frame.width, frame.height);
    let mut hue_ok = [false; 256];
    for (h, ok) in hue_ok.iter_mut().enumerate().take(HUE_MAX as usize + 1) {
        *ok = range.contains([h as u8, range.lower[1], range.lower[2]]);
    }
    let chroma = chroma_intervals(range);
    // A block of pixels none of which can pass the value and saturation
    // tests is skipped after tests the compiler vectorises; the exact test
    // runs only on the other blocks. The first, on bytes, asks for the
    // value range and the smallest chroma that passes at any value. The
    // second, on 16 bits and only where the first found candidates, asks
    // for the saturation: OpenCV's is `255 diff / v` rounded, so a pixel
    // that passes has `255 diff / v > s_lo - 1`, that is
    // `255 diff + v > s_lo v`, and `255 diff / v < s_hi + 1` (the bound
    // that keeps a white rope's range off a saturated table). The third, on bytes and only where the
    // second found candidates, asks for the sixths of the hue circle the
    // hue range meets (`hue_sectors`): a table as saturated as the rope is
    // told from it by hue alone. All keep every pixel the exact test may take.
    let (v_lo, v_hi) = (range.lower[2], range.upper[2]);
    let noise = range.chroma_noise;
    let s_lo = u16::from(range.lower[1]);
    let s_hi_next = u16::from(range.upper[1]) + 1;
    let least_diff = chroma
        .iter()
        .filter(|c| c.1 > 0)
        .map(|c| c.0)
        .min()
        .map_or(u8::MAX, |d| d.min(255) as u8);
    let sectors = hue_sectors(range);
    let all_hues = sectors == [1; 6];
    let color = frame.color;
    // How often the first pre-test ran and passed over the last window of
    // blocks, and whether it is skipped in this one.
    let (mut runs, mut passes, mut skipping) = (0usize, 0usize, false);
    for (k, m) in mask.data.chunks_mut(SEGMENT_BLOCK).enumerate() {
        let start = 3 * SEGMENT_BLOCK * k;
        let block = &color[start..(start + 3 * m.len()).min(color.len())];
        // Channel maximum and minimum at every byte over the next three,
        // kept only at the bytes that start a pixel: contiguous lanes of a
        // fixed count, so it vectorises. The last block, with no two bytes
        // after it, goes straight to the exact test.
        let lanes = |o: usize| -> Option<&[u8; 3 * SEGMENT_BLOCK]> {
            color
                .get(start + o..start + o + 3 * SEGMENT_BLOCK)?
                .try_into()
                .ok()
        };
        if let (Some(r), Some(g), Some(b)) = (lanes(0), lanes(1), lanes(2)) {
            // Where the first pre-test passes most blocks (a table whose
            // colour is near the rope's) it only adds to the second: over
            // a window of blocks after one where it passed more than three
            // in four, it runs on one block in FIRST_PRETEST_PERIOD, to
            // keep count. Every pre-test keeps every pixel the exact test
            // may take, so skipping one changes nothing but the time.
            if k % PRETEST_WINDOW == 0 {
                skipping = 4 * passes > 3 * runs;
                (runs, passes) = (0, 0);
            }
            if !skipping || k % FIRST_PRETEST_PERIOD == 0 {
                let mut candidates = 0u8;
                for i in 0..3 * SEGMENT_BLOCK {
                    let (hi, lo) = (r[i].max(g[i]).max(b[i]), r[i].min(g[i]).min(b[i]));
                    candidates |= PIXEL_STARTS[i]
                        & u8::from(hi >= v_lo && hi <= v_hi && hi - lo >= least_diff);
                }
                runs += 1;
                if candidates == 0 {
                    continue;
                }
                passes += 1;
            }
            let saturated = if s_hi_next <= 255 {
                may_be_saturated::<true>([r, g, b], s_lo, s_hi_next, noise)
            } else {
                may_be_saturated::<false>([r, g, b], s_lo, s_hi_next, noise)
            };
            if !saturated {
                continue;
            }
            if !all_hues {
                let mut hued = 0u8;
                for i in 0..3 * SEGMENT_BLOCK {
                    hued |= PIXEL_STARTS[i] & in_hue_sectors(&sectors, r[i], g[i], b[i]);
                }
                if hued == 0 {
                    continue;
                }
            }
        }
        for (px, m) in block.chunks_exact(3).zip(m) {
            let (r, g, b) = (px[0] as i32, px[1] as i32, px[2] as i32);
            let v = r.max(g).max(b);
            let diff = v - r.min(g).min(b);
            let (first, count) = chroma[v as usize];
            if ((diff - first) as u32) < count {
                *m = hue_ok[hue(r, g, b, v, diff) as usize];
            }
        }
    }
    let black_in_range = range.contains(rgb_to_hsv([0, 0, 0]));
    let width = frame.width as usize;
    for rect in occlusions {
        if let Some((x0, x1, y0, y1)) = rect.clip(frame.width, frame.height) {
            for v in y0..y1 {
                mask.data[v * width + x0..v * width + x1].fill(black_in_range);
            }
        }
    }
    mask
}

/// [`segment`] compiled for wider vector registers, chosen at run time.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
mod wide {
    use super::{segment_portable, Frame, HsvRange, Mask, Rect};

    /// The variants, widest first.
    #[derive(Clone, Copy)]
    enum Width {
        Avx512,
        Avx2,
    }

    const WIDEST_FIRST: [Width; 2] = [Width::Avx512, Width::Avx2];

    impl Width {
        /// Whether this processor has the variant's features (AVX-512BW
        /// implies AVX-512F).
        fn available(self) -> bool {
            match self {
                Width::Avx512 => std::is_x86_feature_detected!("avx512bw"),
                Width::Avx2 => std::is_x86_feature_detected!("avx2"),
            }
        }

        fn name(self) -> &'static str {
            match self {
                Width::Avx512 => "AVX-512",
                Width::Avx2 => "AVX2",
            }
        }

        /// The mask from this variant, `None` when the processor lacks it.
        fn segment(self, frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Option<Mask> {
            if !self.available() {
                return None;
            }
            // SAFETY: the processor has the features the variant is
            // compiled for (checked just above).
            #[allow(unsafe_code)]
            Some(unsafe {
                match self {
                    Width::Avx512 => avx512(frame, range, occlusions),
                    Width::Avx2 => avx2(frame, range, occlusions),
                }
            })
        }
    }

    /// The name of the variant [`segment`] runs, `None` for the portable one.
    pub(super) fn name() -> Option<&'static str> {
        WIDEST_FIRST
            .into_iter()
            .find(|w| w.available())
            .map(Width::name)
    }

    /// The mask from the widest variant this processor runs, `None` when
    /// it has neither AVX-512BW nor AVX2.
    pub(super) fn segment(
        frame: &Frame<'_>,
        range: &HsvRange,
        occlusions: &[Rect],
    ) -> Option<Mask> {
        WIDEST_FIRST
            .into_iter()
            .find_map(|w| w.segment(frame, range, occlusions))
    }

    /// Every variant this processor runs, by name, for the tests to
    /// compare with the portable one.
    #[cfg(test)]
    pub(super) fn each(
        frame: &Frame<'_>,
        range: &HsvRange,
        occlusions: &[Rect],
    ) -> alloc::vec::Vec<(&'static str, Mask)> {
        WIDEST_FIRST
            .into_iter()
            .filter_map(|w| Some((w.name(), w.segment(frame, range, occlusions)?)))
            .collect()
    }

    // `unsafe fn`: a safe function with `target_feature` needs Rust 1.86,
    // and the workspace's `rust-version` is 1.85.
    /// # Safety
    /// The processor has AVX-512F and AVX-512BW.
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx512f,avx512bw")]
    unsafe fn avx512(frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Mask {
        segment_portable(frame, range, occlusions)
    }

    /// # Safety
    /// The processor has AVX2.
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2(frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Mask {
        segment_portable(frame, range, occlusions)
    }
}

/// The parts of `mask` wider than `max_width` pixels, taken out: where a
/// disc of that diameter fits (its centre has mask pixels at half the
/// diameter in all eight directions; centres looked for on a grid of a
/// quarter of the diameter), the mask pixels within half the diameter and
/// a grid step of such a centre (eight-neighbour steps through the mask). `None` when no part is that
/// wide (the mask stays as it is); else the mask without them, and how many
/// pixels were taken out. A thin rope, even where it crosses itself, has
/// no such part; a phone beside it does, and a rope touching the phone
/// loses only what lies within that reach of it.
pub fn without_wide_parts(mask: &Mask, max_width: f64) -> Option<(Mask, usize)> {
    if !(max_width >= 2.0) {
        return None;
    }
    let r = libm::round(0.5 * max_width).min(f64::from(u8::MAX / 2)) as i64;
    let (w, h) = (mask.width as i64, mask.height as i64);
    if 2 * r >= w || 2 * r >= h {
        return None;
    }
    // Centres are looked for on a grid of half the radius (the centres of
    // a part wider than the diameter fill a region, which the grid meets
    // unless the part is barely wider): 1 / s^2 of the pixels, nine
    // lookups each.
    let step = (r / 2).max(1);
    let at = |u: i64, v: i64| mask.data[(v * w + u) as usize];
    let mut queue = Vec::new();
    let mut v = r;
    while v < h - r {
        let mut u = r;
        while u < w - r {
            if at(u, v)
                && at(u - r, v)
                && at(u + r, v)
                && at(u, v - r)
                && at(u, v + r)
                && at(u - r, v - r)
                && at(u + r, v - r)
                && at(u - r, v + r)
                && at(u + r, v + r)
            {
                queue.push((v * w + u) as usize);
            }
            u += step;
        }
        v += step;
    }
    // The pixels between grid centres are within a grid step more.
    let r = r + step;
    if queue.is_empty() {
        return None;
    }
    // Steps from the nearest centre, through the mask, up to r: a pixel
    // taken out of `kept` is visited. Entries carry their column and row
    // (no division per pixel).
    let mut kept = mask.clone();
    let (wu, hu) = (w as usize, h as usize);
    let mut todo: Vec<(usize, usize, usize, u8)> =
        queue.iter().map(|&i| (i, i % wu, i / wu, 0u8)).collect();
    for &i in &queue {
        kept.data[i] = false;
    }
    let mut k = 0;
    while k < todo.len() {
        let (i, u, v, at_step) = todo[k];
        k += 1;
        let next = at_step + 1;
        if i64::from(next) > r {
            continue;
        }
        // All eight neighbours: steps through the mask then measure the
        // largest of the two offsets, as the nine-pixel test does, and a
        // wide part's corners are reached (side steps alone leave them: a
        // speck at each corner of a phone, far outliers that inflate EM's
        // first variance).
        let (left, right, up, down) = (u > 0, u + 1 < wu, v > 0, v + 1 < hu);
        let sides = [
            left.then(|| (i - 1, u.wrapping_sub(1), v)),
            right.then(|| (i + 1, u + 1, v)),
            up.then(|| (i - wu, u, v.wrapping_sub(1))),
            down.then(|| (i + wu, u, v + 1)),
            (left && up).then(|| (i - wu - 1, u.wrapping_sub(1), v.wrapping_sub(1))),
            (right && up).then(|| (i - wu + 1, u + 1, v.wrapping_sub(1))),
            (left && down).then(|| (i + wu - 1, u.wrapping_sub(1), v + 1)),
            (right && down).then(|| (i + wu + 1, u + 1, v + 1)),
        ];
        for (j, ju, jv) in sides.into_iter().flatten() {
            if kept.data[j] {
                kept.data[j] = false;
                todo.push((j, ju, jv, next));
            }
        }
    }
    let taken = todo.len();
    Some((kept, taken))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The portable segmentation's mask, after checking that every variant
    /// compiled for wider registers this processor runs gives the same.
    fn segment(frame: &Frame<'_>, range: &HsvRange, occlusions: &[Rect]) -> Mask {
        let mask = segment_portable(frame, range, occlusions);
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        for (name, wide) in wide::each(frame, range, occlusions) {
            assert!(
                wide == mask,
                "the {name} segmentation differs from the portable one"
            );
        }
        assert!(super::segment(frame, range, occlusions) == mask);
        mask
    }

    #[test]
    fn a_mask_includes_another_of_its_size_only() {
        let mut a = Mask::new(3, 2);
        let mut b = Mask::new(3, 2);
        (a.data[0], b.data[4]) = (true, true);
        a.include(&b);
        assert_eq!(a.count(), 2);
        let mut other = Mask::new(2, 3);
        other.data.fill(true);
        a.include(&other);
        assert_eq!(a.count(), 2);
    }

    #[test]
    fn hsv_matches_opencv_on_primary_and_mixed_colours() {
        // Values computed with OpenCV's formula by hand.
        assert_eq!(rgb_to_hsv([255, 0, 0]), [0, 255, 255]);
        assert_eq!(rgb_to_hsv([0, 255, 0]), [60, 255, 255]);
        assert_eq!(rgb_to_hsv([0, 0, 255]), [120, 255, 255]);
        assert_eq!(rgb_to_hsv([0, 255, 255]), [90, 255, 255]);
        assert_eq!(rgb_to_hsv([0, 0, 0]), [0, 0, 0]);
        assert_eq!(rgb_to_hsv([128, 128, 128]), [0, 0, 128]);
        // A rope blue like TrackDLO's: v = b, h = 240 + 60 (r - g) / diff = 216 deg -> 108;
        // s = 255 * 100 / 120 = 212.5 -> 213 with OpenCV's fixed-point rounding.
        assert_eq!(rgb_to_hsv([20, 60, 120]), [108, 213, 120]);
        // Magenta wraps: v = r = b; OpenCV takes the r branch: h = 60 (g - b)/diff = -60 deg -> 150.
        assert_eq!(rgb_to_hsv([255, 0, 255]), [150, 255, 255]);
    }

    /// The fixed-point conversion against HSV's definition in floating point
    /// (OpenCV's 8-bit scaling: H = hue in degrees / 2, S = 255 diff / V),
    /// on every colour of a grid: never more than one unit apart (the
    /// tables round once more), and equal on 97 % of the colours.
    #[test]
    fn hsv_follows_its_definition_over_an_rgb_grid() {
        let (mut total, mut equal) = (0, 0);
        for r in (0..=255).step_by(3) {
            for g in (0..=255).step_by(3) {
                for b in (0..=255).step_by(3) {
                    let (rf, gf, bf) = (r as f64, g as f64, b as f64);
                    let v = rf.max(gf).max(bf);
                    let diff = v - rf.min(gf).min(bf);
                    let s_ref = if v > 0.0 { 255.0 * diff / v } else { 0.0 };
                    let h_deg = if diff == 0.0 {
                        0.0
                    } else if v == rf {
                        60.0 * (gf - bf) / diff
                    } else if v == gf {
                        120.0 + 60.0 * (bf - rf) / diff
                    } else {
                        240.0 + 60.0 * (rf - gf) / diff
                    };
                    let h_ref = (h_deg / 2.0).rem_euclid(180.0);
                    let [h, s, vv] = rgb_to_hsv([r as u8, g as u8, b as u8]);
                    assert_eq!(vv as f64, v);
                    let dh = (h as f64 - h_ref).abs();
                    let dh = dh.min(180.0 - dh);
                    assert!(dh <= 1.0, "{r} {g} {b}: h {h} vs {h_ref}");
                    assert!(
                        (s as f64 - s_ref).abs() <= 1.0,
                        "{r} {g} {b}: s {s} vs {s_ref}"
                    );
                    total += 1;
                    if (h as f64 - libm::round(h_ref) % 180.0).abs() < 0.5
                        && (s as f64 - libm::round(s_ref)).abs() < 0.5
                    {
                        equal += 1;
                    }
                }
            }
        }
        // Measured: 617723 of 636056 (97.1 %); the rest are rounding ties.
        assert!(equal as f64 >= 0.965 * total as f64, "{equal} of {total}");
    }

    /// The fast path (value and saturation first, hue table) agrees with
    /// `rgb_to_hsv` + `contains` on every colour of a coarse RGB grid.
    #[test]
    fn segment_agrees_with_the_plain_conversion() {
        let mut color = Vec::new();
        for r in (0..256).step_by(5) {
            for g in (0..256).step_by(5) {
                for b in (0..256).step_by(5) {
                    color.extend_from_slice(&[r as u8, g as u8, b as u8]);
                }
            }
        }
        let n = color.len() / 3; // 52^3 = 2704 x 52
        let depth = alloc::vec![0u16; n];
        let f = Frame::new(2704, 52, &color, &depth, 0.001).expect("frame");
        for range in [
            HsvRange::default(),
            HsvRange::new([170, 50, 40], [8, 230, 250]),
            HsvRange::new([0, 0, 0], [179, 255, 255]),
            // A grey rope's range: its own saturation, 20 levels of noise.
            HsvRange {
                lower: [0, 0, 40],
                upper: [179, 12, 255],
                chroma_noise: 20,
            },
            HsvRange {
                lower: [0, 20, 40],
                upper: [179, 120, 200],
                chroma_noise: 7,
            },
        ] {
            let m = segment(&f, &range, &[]);
            for (i, px) in color.chunks_exact(3).enumerate() {
                assert_eq!(
                    m.data[i],
                    range.contains_rgb([px[0], px[1], px[2]]),
                    "{px:?} {range:?}"
                );
            }
        }
    }

    /// The hue pre-test never rejects a colour whose OpenCV hue is in the
    /// range: every colour of a grid (with the channels' extremes and
    /// ties), for hue ranges all round the circle, wrapping ones included.
    /// And it does reject: a green range leaves out most colours, and a
    /// range of one sixth all colours of the opposite sixths.
    #[test]
    fn hue_sectors_keep_every_colour_in_range_and_reject_the_others() {
        let levels: Vec<u8> = (0..=255u8).step_by(5).chain([1, 2, 254]).collect();
        for lo in (0..=HUE_MAX).step_by(7) {
            for hi in (0..=HUE_MAX).step_by(11) {
                let range = HsvRange::new([lo, 0, 0], [hi, 255, 255]);
                let sectors = hue_sectors(&range);
                let mut rejected = 0usize;
                for &r in &levels {
                    for &g in &levels {
                        for &b in &levels {
                            let hsv = rgb_to_hsv([r, g, b]);
                            let kept = in_hue_sectors(&sectors, r, g, b) == 1;
                            assert!(
                                kept || !range.contains(hsv),
                                "{lo}..{hi} ({sectors:?}): rgb {r} {g} {b} has hue {}",
                                hsv[0]
                            );
                            rejected += usize::from(!kept);
                        }
                    }
                }
                if (lo, hi) == (49, 77) {
                    let all = levels.len().pow(3);
                    assert!(rejected * 2 > all, "{rejected} of {all}");
                }
            }
        }
        let green = HsvRange::new([35, 0, 0], [85, 255, 255]);
        assert_eq!(hue_sectors(&green), [0, 1, 1, 0, 0, 0]);
        let red = HsvRange::new([170, 0, 0], [8, 255, 255]);
        assert_eq!(hue_sectors(&red), [1, 0, 0, 0, 0, 1]);
        let everything = HsvRange::new([5, 0, 0], [3, 255, 255]);
        assert_eq!(hue_sectors(&everything), [1; 6]);
    }

    /// The block pre-test may skip a block only when no pixel of it is in
    /// range: images of sizes that leave a partial last block, mostly grey
    /// with rope-coloured pixels scattered at block edges, many ranges.
    #[test]
    fn skipped_blocks_hold_no_rope_pixel_and_the_last_partial_block_is_tested() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for (width, height) in [(37u32, 29u32), (640, 3), (31, 1), (33, 2)] {
            let n = (width * height) as usize;
            let mut color = alloc::vec![0u8; 3 * n];
            for (i, px) in color.chunks_exact_mut(3).enumerate() {
                let grey = rng.below(256) as u8;
                let rope = rng.below(9) == 0 || i % SEGMENT_BLOCK == 0 || i + 1 == n;
                let rgb = if rope {
                    [
                        rng.below(256) as u8,
                        rng.below(256) as u8,
                        rng.below(256) as u8,
                    ]
                } else {
                    [grey, grey.saturating_add(rng.below(4) as u8), grey]
                };
                px.copy_from_slice(&rgb);
            }
            let depth = alloc::vec![0u16; n];
            let f = Frame::new(width, height, &color, &depth, 0.001).expect("frame");
            for _ in 0..40 {
                let mut lower = [0u8; 3];
                let mut upper = [0u8; 3];
                for c in 0..3 {
                    let top = if c == 0 { 180 } else { 256 };
                    let (a, b) = (rng.below(top) as u8, rng.below(top) as u8);
                    // Hue may wrap (lower > upper); S and V are ordered.
                    (lower[c], upper[c]) = if c == 0 { (a, b) } else { (a.min(b), a.max(b)) };
                }
                let range = HsvRange::new(lower, upper);
                let m = segment(&f, &range, &[]);
                for (i, px) in color.chunks_exact(3).enumerate() {
                    let want = range.contains(rgb_to_hsv([px[0], px[1], px[2]]));
                    assert_eq!(
                        m.data[i], want,
                        "{width}x{height} pixel {i} {px:?} {range:?}"
                    );
                }
            }
        }
    }

    /// A table that passes the first pre-test everywhere (bright, a little
    /// coloured, not saturated enough) makes it skipped on most blocks:
    /// rope pixels in any block, sampled or not, are still found.
    #[test]
    fn rope_pixels_on_a_table_near_the_rope_s_colour_are_found_where_the_first_pretest_is_skipped()
    {
        let (width, height) = (640usize, 6usize);
        let table = [150u8, 120, 110];
        let rope = [200u8, 40, 30];
        let range = HsvRange::new([0, 120, 60], [10, 255, 255]);
        let mut color = table.repeat(width * height);
        let mut want = alloc::vec![false; width * height];
        // One rope pixel in each of the blocks of the later rows: skipped
        // and sampled ones alike.
        for i in (2 * width..width * height).step_by(SEGMENT_BLOCK + 1) {
            color[3 * i..3 * i + 3].copy_from_slice(&rope);
            want[i] = true;
        }
        assert!(!range.contains_rgb(table) && range.contains_rgb(rope));
        let depth = alloc::vec![0u16; width * height];
        let f = Frame::new(width as u32, height as u32, &color, &depth, 0.001).expect("frame");
        assert_eq!(segment(&f, &range, &[]).data, want);
    }

    /// A block whose only candidate is a pixel at the smallest chroma that
    /// reaches the saturation bound is not skipped: one such pixel per
    /// block, in grey, for every value and many bounds.
    #[test]
    fn a_lone_pixel_just_saturated_enough_keeps_its_block() {
        for s_lo in (2..=255).step_by(7) {
            let mut color = Vec::new();
            let mut want = Vec::new();
            for v in 1..=255i32 {
                let Some(d) = (0..=v).find(|&d| saturation(v, d) >= s_lo) else {
                    continue;
                };
                let mut block = [[50u8; 3]; SEGMENT_BLOCK];
                block[7] = [v as u8, (v - d) as u8, (v - d) as u8];
                color.extend(block.iter().flatten());
                want.extend((0..SEGMENT_BLOCK).map(|i| i == 7));
            }
            // A trailing grey block, so that every tested block has two bytes after it.
            color.extend([50u8; 3 * SEGMENT_BLOCK]);
            want.extend([false; SEGMENT_BLOCK]);
            let n = want.len();
            let depth = alloc::vec![0u16; n];
            let f = Frame::new(n as u32, 1, &color, &depth, 0.001).expect("frame");
            let range = HsvRange::new([0, s_lo as u8, 0], [179, 255, 255]);
            assert_eq!(segment(&f, &range, &[]).data, want, "s_lo {s_lo}");
        }
    }

    /// The same at the upper saturation bound: a block of saturated red
    /// (above every bound tried) with one pixel at the largest chroma
    /// that stays within the bound is not skipped, for every value.
    #[test]
    fn a_lone_pixel_just_unsaturated_enough_keeps_its_block() {
        for s_hi in (0..255).step_by(7) {
            let mut color = Vec::new();
            let mut want = Vec::new();
            for v in 0..=255i32 {
                let Some(d) = (0..=v).rev().find(|&d| saturation(v, d) <= s_hi) else {
                    continue;
                };
                let mut block = [[200u8, 0, 0]; SEGMENT_BLOCK];
                block[11] = [v as u8, (v - d) as u8, (v - d) as u8];
                color.extend(block.iter().flatten());
                want.extend((0..SEGMENT_BLOCK).map(|i| i == 11));
            }
            color.extend([200u8, 0, 0].repeat(SEGMENT_BLOCK));
            want.extend([false; SEGMENT_BLOCK]);
            if want.len() % 2 == 1 {
                color.extend([200u8, 0, 0]);
                want.push(false);
            }
            // Two rows: blocks run on across rows, and one row would be
            // wider than an image may be.
            let n = want.len();
            let depth = alloc::vec![0u16; n];
            let f = Frame::new(n as u32 / 2, 2, &color, &depth, 0.001).expect("frame");
            let range = HsvRange::new([0, 0, 0], [179, s_hi as u8, 255]);
            assert_eq!(segment(&f, &range, &[]).data, want, "s_hi {s_hi}");
        }
    }

    /// The value-and-saturation table against both tests, for every value
    /// and chroma, over a grid of saturation and value bounds.
    #[test]
    fn chroma_intervals_hold_exactly_the_passing_chroma() {
        for s_lo in (0..=255).step_by(17) {
            for s_hi in (s_lo..=255).step_by(23) {
                let range = HsvRange::new([0, s_lo as u8, 30], [179, s_hi as u8, 240]);
                let table = chroma_intervals(&range);
                for v in 0..256i32 {
                    for d in 0..=v {
                        let s = saturation(v, d);
                        let want = (30..=240).contains(&v) && s >= s_lo && s <= s_hi;
                        let (first, count) = table[v as usize];
                        assert_eq!(
                            ((d - first) as u32) < count,
                            want,
                            "v {v} diff {d} s {s_lo}..{s_hi}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_picked_range_contains_its_colour_and_wraps_for_red() {
        for rgb in [
            [20, 60, 200],
            [200, 30, 40],
            [128, 128, 128],
            [5, 5, 5],
            [255, 255, 255],
        ] {
            let r = HsvRange::around(rgb);
            assert!(r.validate().is_ok(), "{rgb:?}");
            let hsv = rgb_to_hsv(rgb);
            assert!(r.contains(hsv), "{rgb:?} {hsv:?} {r:?}");
            // Coloured picks never reach grey or black.
            if !HsvRange::is_achromatic(hsv) {
                assert!(r.lower[1] >= PICK_MIN_SATURATION && r.lower[2] >= PICK_MIN_VALUE);
            }
        }
        // Pure red has hue 0: the range wraps from 168 to 12.
        let r = HsvRange::around([255, 0, 0]);
        assert_eq!((r.lower[0], r.upper[0]), (168, 12));
        // Blue (S 229, V 200): saturation and value reach 70 and 90 below.
        assert_eq!(rgb_to_hsv([20, 60, 200])[1..], [229, 200]);
        assert_eq!(HsvRange::around([20, 60, 200]).lower[1..], [159, 110]);
    }

    /// A black cable's pixels are dark with a hue and saturation that
    /// swing with the camera's noise: the range picked on one of them takes
    /// the others whatever their hue, and not a light desk or a coloured
    /// rope; one picked on grey takes no saturated colour.
    #[test]
    fn a_dark_or_grey_click_picks_an_achromatic_range() {
        let black = HsvRange::around([9, 10, 8]);
        for px in [[9, 10, 8], [14, 9, 6], [6, 6, 13], [0, 0, 0], [30, 28, 33]] {
            assert!(black.contains(rgb_to_hsv(px)), "{px:?} {black:?}");
        }
        for px in [[200, 170, 120], [128, 128, 128], [20, 60, 200]] {
            assert!(!black.contains(rgb_to_hsv(px)), "{px:?} {black:?}");
        }
        let grey = HsvRange::around([150, 150, 146]);
        assert!(grey.contains_rgb([120, 118, 122]));
        assert!(!grey.contains_rgb([200, 60, 40]));
        assert!(!grey.contains_rgb([20, 20, 20]));
        // The rope's shaded side: a few levels of noise there are a large
        // saturation (53, where the click has 7), not a large chroma (18).
        assert_eq!(rgb_to_hsv([80, 68, 86])[1], 53);
        assert!(grey.contains_rgb([80, 68, 86]));
        // Half the clicked value is the shaded side's floor.
        assert!(grey.contains_rgb([75, 75, 75]) && !grey.contains_rgb([74, 74, 74]));
        // A shaded wooden table is as dark, and far from grey.
        assert!(!grey.contains_rgb([110, 80, 55]));
    }

    /// A 5 px line crossing another at right angles, and touching a 40 x
    /// 30 block: the block goes, the lines stay but for the pixels within
    /// reach of the block's wide part.
    #[test]
    fn wide_parts_go_and_thin_crossing_lines_stay() {
        let (w, h) = (120usize, 80usize);
        let mut mask = Mask::new(w as u32, h as u32);
        let mut set = |u0: usize, u1: usize, v0: usize, v1: usize| {
            for v in v0..v1 {
                for u in u0..u1 {
                    mask.data[v * w + u] = true;
                }
            }
        };
        set(5, 100, 20, 25); // horizontal line, 5 px
        set(40, 45, 2, 78); // vertical line crossing it
        set(70, 110, 25, 55); // block touching the horizontal line from below
        let before = mask.count();
        // A rope 5 px wide: parts wider than 10 px go.
        let (kept, gone) = without_wide_parts(&mask, 10.0).expect("the block is wide");
        assert_eq!(kept.count() + gone, before);
        assert!(!kept.get(90, 40), "the block's middle stays");
        // Nothing of the block stays, its corners included (side steps alone
        // left a speck at each: far outliers for the tracker).
        for v in 25..55 {
            for u in 70..110 {
                assert!(!kept.get(u, v), "({u}, {v}) of the block stays");
            }
        }
        assert!(kept.get(42, 22), "the crossing went");
        assert!(kept.get(20, 22) && kept.get(42, 70), "the lines went");
        // The block: 1200 px; what goes is the block and the line's pixels
        // within 5 steps of it.
        assert!((1200..1200 + 5 * 5 * 10).contains(&gone), "{gone}");
        // Thin lines alone: nothing to take out.
        let mut lines = kept.clone();
        for v in 25..55 {
            for u in 70..110 {
                lines.data[v * w + u] = false;
            }
        }
        assert!(without_wide_parts(&lines, 10.0).is_none());
        assert!(without_wide_parts(&mask, f64::NAN).is_none());
    }

    #[test]
    fn rectangles_and_masks_answer_for_their_own_pixels_only() {
        let r = Rect {
            x: 2,
            y: 3,
            w: 4,
            h: 2,
        };
        let inside: Vec<(i64, i64)> = (0..10)
            .flat_map(|v| (0..10).map(move |u| (u, v)))
            .filter(|&(u, v)| r.contains(u, v))
            .collect();
        let expect: Vec<(i64, i64)> = (3..5).flat_map(|v| (2..6).map(move |u| (u, v))).collect();
        assert_eq!(inside, expect);
        assert_eq!(r.clip(4, 4), Some((2, 4, 3, 4)));
        assert_eq!(r.clip(2, 10), None);
        assert_eq!(
            Rect {
                x: 0,
                y: 0,
                w: 0,
                h: 5
            }
            .clip(10, 10),
            None
        );
        let mut m = Mask::new(3, 2);
        m.data[5] = true;
        assert!(m.get(2, 1));
        let mut corner = Mask::new(3, 2);
        corner.data[0] = true;
        assert!(corner.get(0, 0) && !corner.get(-1, 0) && !corner.get(0, -1));
        for (u, v) in [(3, 1), (2, 2), (-1, 1), (2, -1), (0, 0), (1, 1)] {
            assert!(!m.get(u, v), "({u}, {v})");
        }
        assert_eq!(m.count(), 1);
    }

    #[test]
    fn the_hsv_box_needs_every_channel_inside() {
        let r = HsvRange::new([100, 50, 60], [120, 200, 210]);
        assert!(r.contains([110, 100, 100]));
        for hsv in [
            [99, 100, 100],
            [121, 100, 100],
            [110, 49, 100],
            [110, 201, 100],
            [110, 100, 59],
            [110, 100, 211],
        ] {
            assert!(!r.contains(hsv), "{hsv:?}");
        }
        // Equal bounds are a valid (one-value) range.
        assert!(HsvRange::new([0, 100, 50], [179, 100, 50])
            .validate()
            .is_ok());
        // Hue 179 is the last valid one.
        assert!(HsvRange::new([0, 0, 0], [179, 255, 255]).validate().is_ok());
        assert!(HsvRange::new([180, 0, 0], [179, 255, 255])
            .validate()
            .is_err());
    }

    #[test]
    fn hue_range_wraps_through_zero() {
        let red = HsvRange::new([170, 100, 50], [10, 255, 255]);
        assert!(red.validate().is_ok());
        assert!(red.contains([175, 200, 200]));
        assert!(red.contains([5, 200, 200]));
        assert!(!red.contains([90, 200, 200]));
    }

    #[test]
    fn bad_ranges_are_rejected() {
        let r = HsvRange::new([0, 200, 0], [179, 100, 255]);
        assert!(matches!(
            r.validate(),
            Err(SegmentationError::InvertedRange {
                channel: "saturation",
                ..
            })
        ));
        let r = HsvRange::new([0, 0, 0], [200, 255, 255]);
        assert!(matches!(
            r.validate(),
            Err(SegmentationError::HueOutOfRange { value: 200 })
        ));
    }

    #[test]
    fn occlusion_rectangles_black_out_pixels_and_clip_to_the_image() {
        let color: Vec<u8> = [20u8, 60, 120].repeat(16);
        let depth = [600u16; 16];
        let f = Frame::new(4, 4, &color, &depth, 0.001).expect("frame");
        let range = HsvRange::default();
        let m = segment(&f, &range, &[]);
        assert_eq!(m.count(), 16);
        let rects = [
            Rect {
                x: -2,
                y: -2,
                w: 3,
                h: 3,
            },
            Rect {
                x: 3,
                y: 3,
                w: 100,
                h: 100,
            },
            Rect {
                x: 50,
                y: 50,
                w: 5,
                h: 5,
            },
        ];
        let m = segment(&f, &range, &rects);
        assert_eq!(m.count(), 14);
        assert!(!m.get(0, 0) && !m.get(3, 3) && m.get(1, 1));
    }
}
