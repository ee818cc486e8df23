//! Scene variants: the same scenario seen by another camera (640x480 or
//! 1280x720, tilted, nearer or farther) with another rope (5-20 mm thick,
//! other colours) on another table, so that the tracker is judged on
//! scenes it was not tuned on.

use upetrack::CameraIntrinsics;

use crate::render::RenderSettings;
use crate::rope::RopeSettings;

/// The D435i colour stream at 1280x720.
pub const D435I_1280X720: CameraIntrinsics = CameraIntrinsics {
    width: 1280,
    height: 720,
    fx: 922.5,
    fy: 922.5,
    cx: 640.0,
    cy: 360.0,
};

/// Rope albedos of the variants, RGB in [0, 1].
const BLUE: [f64; 3] = [0.08, 0.22, 0.55];
const RED: [f64; 3] = [0.62, 0.07, 0.06];
const GREEN: [f64; 3] = [0.10, 0.45, 0.15];
const ORANGE: [f64; 3] = [0.85, 0.42, 0.05];
const DARK_BLUE: [f64; 3] = [0.06, 0.12, 0.45];

/// The variants' rope colours by name (the page's scene maker offers them).
pub const ROPE_COLOURS: [(&str, [f64; 3]); 5] = [
    ("blue", BLUE),
    ("red", RED),
    ("green", GREEN),
    ("orange", ORANGE),
    ("dark blue", DARK_BLUE),
];

/// One way of seeing a scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variant {
    /// Name on the command line (`--variant`).
    pub name: &'static str,
    /// One line on what differs.
    pub description: &'static str,
    /// 1280x720 instead of 640x480.
    pub hd: bool,
    /// Camera tilt from straight down, degrees.
    pub tilt_degrees: f64,
    /// Camera distance to the table's centre, metres.
    pub distance: f64,
    /// Rope diameter, metres.
    pub rope_diameter: f64,
    /// Rope length, metres.
    pub rope_length: f64,
    /// Rope albedo, RGB in [0, 1].
    pub rope_color: [f64; 3],
    /// Table albedo, RGB in [0, 1].
    pub table_color: [f64; 3],
}

impl Variant {
    /// The scenes the project's defaults were first made on: 640x480, straight
    /// down from 0.6 m, a 15 mm blue rope on an off-white table.
    pub const BASE: Self = Self {
        name: "base",
        description: "640x480, straight down from 0.6 m, 15 mm blue rope, off-white table",
        hd: false,
        tilt_degrees: 0.0,
        distance: 0.6,
        rope_diameter: 0.015,
        rope_length: 0.8,
        rope_color: BLUE,
        table_color: [0.86, 0.87, 0.85],
    };

    /// The black cable of `cable-desk`: 640x480, tilted 15 degrees, 0.55 m,
    /// a 5 mm black cable 1 m long on a light wooden desk.
    pub const DESK_BLACK_CABLE: Self = Self {
        name: "desk-black-cable",
        description:
            "640x480, tilted 15 degrees, 0.55 m, a 5 mm black cable 1 m long on a light wooden desk",
        hd: false,
        tilt_degrees: 15.0,
        distance: 0.55,
        rope_diameter: 0.005,
        rope_length: 1.0,
        rope_color: [0.035, 0.035, 0.04],
        table_color: [0.80, 0.68, 0.50],
    };

    /// A green rope on oak at 1280x720: the table is as saturated as the
    /// rope and passes its value and saturation range, so only the hue
    /// tells them apart (the scene where segmentation once took 7x longer).
    pub const HD_GREEN_OAK: Self = Self {
        name: "hd-green-oak",
        description: "1280x720, tilted 20 degrees, 0.7 m, 10 mm green rope on saturated oak",
        hd: true,
        tilt_degrees: 20.0,
        distance: 0.7,
        rope_diameter: 0.010,
        rope_length: 0.8,
        rope_color: GREEN,
        table_color: [0.70, 0.48, 0.26],
    };

    /// Every variant, the base first.
    pub const ALL: [Self; 7] = [
        Self::BASE,
        Self {
            name: "hd-tilted-red",
            description: "1280x720, tilted 25 degrees, 0.7 m, 12 mm red rope on light wood",
            hd: true,
            tilt_degrees: 25.0,
            distance: 0.7,
            rope_diameter: 0.012,
            rope_length: 0.8,
            rope_color: RED,
            table_color: [0.78, 0.64, 0.45],
        },
        Self {
            name: "near-thin-green",
            description:
                "640x480, tilted 10 degrees, 0.45 m, a 6 mm green cable 0.5 m long on grey laminate",
            hd: false,
            tilt_degrees: 10.0,
            distance: 0.45,
            rope_diameter: 0.006,
            rope_length: 0.5,
            rope_color: GREEN,
            table_color: [0.60, 0.61, 0.62],
        },
        Self {
            name: "far-thick-orange",
            description:
                "640x480, tilted 30 degrees, 0.95 m, 20 mm orange rope on dark grey laminate",
            hd: false,
            tilt_degrees: 30.0,
            distance: 0.95,
            rope_diameter: 0.020,
            rope_length: 0.8,
            rope_color: ORANGE,
            table_color: [0.30, 0.31, 0.33],
        },
        Self {
            name: "hd-thin-blue",
            description: "1280x720, straight down from 0.8 m, 5 mm dark blue cord on white",
            hd: true,
            tilt_degrees: 0.0,
            distance: 0.8,
            rope_diameter: 0.005,
            rope_length: 0.8,
            rope_color: DARK_BLUE,
            table_color: [0.92, 0.92, 0.90],
        },
        Self::DESK_BLACK_CABLE,
        Self::HD_GREEN_OAK,
    ];

    /// The variant called `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|v| v.name == name)
    }

    /// Rendering settings for this variant.
    pub fn render(&self) -> RenderSettings {
        RenderSettings {
            camera: if self.hd {
                D435I_1280X720
            } else {
                CameraIntrinsics::D435I_640X480
            },
            camera_height: self.distance,
            camera_tilt: self.tilt_degrees.to_radians(),
            rope_color: self.rope_color,
            table_color: self.table_color,
            ..RenderSettings::default()
        }
    }

    /// The rope for this variant.
    pub fn rope(&self) -> RopeSettings {
        RopeSettings {
            thickness: self.rope_diameter,
            length: self.rope_length,
            ..RopeSettings::default()
        }
    }

    /// `true` for the base variant (the scenario's name alone).
    pub fn is_base(&self) -> bool {
        self.name == Self::BASE.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_base_variant_is_the_default_scene() {
        assert_eq!(Variant::BASE.render(), RenderSettings::default());
        assert_eq!(Variant::BASE.rope(), RopeSettings::default());
        for v in Variant::ALL {
            assert_eq!(Variant::parse(v.name), Some(v));
        }
    }
}
