//! What initialisation reports: the rope-shaped candidates, the one taken
//! and why, and what was set aside with its reason.

use alloc::vec::Vec;

/// Why a shape or a candidate is not the rope.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(tag = "kind", rename_all = "snake_case"))]
pub enum NotRope {
    /// No strand in its skeleton: a compact blob (a phone, a box).
    Compact,
    /// More junctions than a rope has ([`super::MAX_JUNCTION_CELLS`]).
    Branched {
        /// Junction cells.
        junctions: usize,
    },
    /// No depth along it.
    NoDepth,
    /// Thinner or thicker than a rope (or than the prior allows).
    Diameter {
        /// Its width, millimetres.
        diameter_mm: f64,
        /// Thinnest accepted, millimetres.
        low_mm: f64,
        /// Thickest accepted, millimetres.
        high_mm: f64,
    },
    /// Its width varies more than a rope's.
    Uneven {
        /// Share of it within the tolerance of its median width.
        even_share: f64,
    },
    /// Too short for its width.
    Short {
        /// Length over width.
        elongation: f64,
    },
    /// It turns more sharply than a rope can bend.
    Kinked {
        /// The sharpest turn over one width, degrees.
        turn_degrees: f64,
    },
    /// Fewer pixels than `min_blob_pixels`.
    Small {
        /// Its pixels.
        pixels: usize,
    },
    /// Longer than the rope the prior describes.
    LongerThanPrior {
        /// Its length, metres.
        length_m: f64,
        /// The prior's, metres.
        prior_m: f64,
    },
}

impl core::fmt::Display for NotRope {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Compact => write!(f, "compact (no strand in its skeleton)"),
            Self::Branched { junctions } => write!(f, "too branched ({junctions} junctions)"),
            Self::NoDepth => write!(f, "without depth"),
            Self::Diameter {
                diameter_mm,
                low_mm,
                high_mm,
            } => write!(
                f,
                "{diameter_mm:.1} mm wide, outside {low_mm:.1}-{high_mm:.1} mm"
            ),
            Self::Uneven { even_share } => write!(
                f,
                "of uneven width ({:.0} % of it near its median width)",
                even_share * 100.0
            ),
            Self::Short { elongation } => {
                write!(f, "only {elongation:.1} times as long as it is wide")
            }
            Self::Kinked { turn_degrees } => {
                write!(f, "kinked ({turn_degrees:.0} degrees within its width)")
            }
            Self::Small { pixels } => write!(f, "small ({pixels} pixels)"),
            Self::LongerThanPrior { length_m, prior_m } => write!(
                f,
                "longer than the rope ({length_m:.2} m; the rope is {prior_m:.2} m)"
            ),
        }
    }
}

/// A shape (or a joined candidate) that is not the rope.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SetAside {
    /// Its mask pixels.
    pub pixels: usize,
    /// Its centre, image pixels.
    pub centre: [f64; 2],
    /// Why.
    pub reason: NotRope,
}

impl core::fmt::Display for SetAside {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} px at ({:.0}, {:.0}), is {}",
            self.pixels, self.centre[0], self.centre[1], self.reason
        )
    }
}

/// A rope-shaped candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Candidate {
    /// Length, metres, gaps between fragments included.
    pub length: f64,
    /// Diameter, metres.
    pub diameter: f64,
    /// Pieces of mask joined into it.
    pub fragments: usize,
    /// Crossings with itself.
    pub crossings: usize,
    /// Its two ends, image pixels.
    pub ends: [[f64; 2]; 2],
}

/// How the candidate was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum ChoiceRule {
    /// The only rope-shaped candidate.
    Only,
    /// The longest of several.
    Longest,
    /// The one the user clicked.
    Clicked,
    /// The one nearest the last known state (re-initialisation after a loss).
    NearestPrevious,
}

/// What initialisation saw and why it took what it took.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct InitReport {
    /// The rope-shaped candidates, longest first.
    pub candidates: Vec<Candidate>,
    /// Index of the one taken.
    pub chosen: usize,
    /// Why it was taken.
    pub rule: ChoiceRule,
    /// Shapes and candidates that are not the rope, largest first (at most
    /// [`super::MAX_REPORTED_SET_ASIDE`]).
    pub set_aside: Vec<SetAside>,
    /// How many were set aside in all.
    pub set_aside_count: usize,
    /// A click was given but no candidate passes near it.
    pub hint_missed: bool,
    /// The length taken over the prior's, when a prior length is known.
    pub prior_length_ratio: Option<f64>,
}

impl core::fmt::Display for InitReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Some(c) = self.candidates.get(self.chosen) else {
            return write!(f, "no candidate");
        };
        let why = match self.rule {
            ChoiceRule::Only => "the only rope-shaped candidate",
            ChoiceRule::Longest => "the longest rope-shaped candidate",
            ChoiceRule::Clicked => "the candidate clicked",
            ChoiceRule::NearestPrevious => "the candidate nearest the last known rope",
        };
        write!(
            f,
            "{:.2} m long, {:.1} mm thick, {} piece(s), {} crossing(s): {why} of {}",
            c.length,
            c.diameter * 1000.0,
            c.fragments,
            c.crossings,
            self.candidates.len()
        )?;
        if self.hint_missed {
            write!(f, " (no candidate passes near the click)")?;
        }
        if let Some(r) = self.prior_length_ratio {
            write!(f, "; {:.0} % of the rope's known length", r * 100.0)?;
        }
        if self.set_aside_count > 0 {
            write!(f, "; set aside {}", self.set_aside_count)?;
            for (k, s) in self.set_aside.iter().enumerate() {
                write!(f, "{} {s}", if k == 0 { ":" } else { ";" })?;
            }
        }
        Ok(())
    }
}
