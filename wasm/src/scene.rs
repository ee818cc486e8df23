//! Scenes made in the page: the project's simulator and renderer
//! (`upetrack_synth`) run in the worker, writing the contract's files in
//! memory, which the page then opens as it opens a .zip.

use serde::{Deserialize, Serialize};
use upetrack_io::source::{MemorySource, Source};
use upetrack_io::synthetic::SyntheticWriter;
use upetrack_synth::scenario::MAX_KNOB_SCALE;
use upetrack_synth::MAX_FRAMES;
use upetrack_synth::{Scenario, ScenarioKind, SceneKnobs, Variant};
use wasm_bindgen::prelude::*;

use crate::{js_err, to_js};

/// Most frames the page generates at once (about 270 KB each in memory).
pub const MAX_SCENE_FRAMES: usize = 600;

/// Rope colours offered: the scene variants' own.
pub use upetrack_synth::variant::ROPE_COLOURS;

/// What the page asks for.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneOptions {
    scenario: String,
    frames: usize,
    seed: u64,
    #[serde(default)]
    variant: Option<String>,
    /// One of [`ROPE_COLOURS`]; the variant's own when absent.
    #[serde(default)]
    rope_colour: Option<String>,
    #[serde(default = "one")]
    occluder_scale: f64,
    #[serde(default = "one")]
    pull_scale: f64,
}

fn one() -> f64 {
    1.0
}

#[derive(Serialize)]
struct Choice {
    name: String,
    description: String,
}

#[derive(Serialize)]
struct Choices {
    scenarios: Vec<Choice>,
    variants: Vec<Choice>,
    colours: Vec<String>,
    max_frames: usize,
    max_scale: f64,
}

/// The scenarios, variants and rope colours the generator offers.
#[wasm_bindgen(js_name = sceneChoices)]
pub fn scene_choices() -> Result<JsValue, JsError> {
    let mut scenarios: Vec<Choice> = ScenarioKind::EXAMPLES
        .iter()
        .filter(|k| !matches!(k, ScenarioKind::OcclusionSweep { .. }))
        .map(|k| Choice {
            name: k.name(),
            description: k.description().into(),
        })
        .collect();
    for percent in [10, 30, 50, 70] {
        let k = ScenarioKind::OcclusionSweep { percent };
        scenarios.push(Choice {
            name: k.name(),
            description: k.description().into(),
        });
    }
    to_js(&Choices {
        scenarios,
        variants: Variant::ALL
            .iter()
            .map(|v| Choice {
                name: v.name.into(),
                description: v.description.into(),
            })
            .collect(),
        colours: ROPE_COLOURS.iter().map(|c| c.0.to_string()).collect(),
        max_frames: MAX_SCENE_FRAMES,
        max_scale: MAX_KNOB_SCALE,
    })
}

/// A scene being generated; once done, its files are read like an archive's.
#[wasm_bindgen]
pub struct SynthScene {
    writer: SyntheticWriter,
    files: MemorySource,
    total: usize,
}

#[wasm_bindgen]
impl SynthScene {
    /// A scene from `{scenario, frames, seed, variant?, rope_colour?,
    /// occluder_scale?, pull_scale?}`; every value is checked.
    #[wasm_bindgen(constructor)]
    pub fn new(options: JsValue) -> Result<SynthScene, JsError> {
        let o: SceneOptions = serde_wasm_bindgen::from_value(options).map_err(js_err)?;
        let kind = ScenarioKind::parse(&o.scenario)
            .ok_or_else(|| JsError::new(&format!("no scenario named `{}`", o.scenario)))?;
        if o.frames == 0 || o.frames > MAX_SCENE_FRAMES.min(MAX_FRAMES) {
            return Err(JsError::new(&format!(
                "frames must be in 1..={MAX_SCENE_FRAMES}, not {}",
                o.frames
            )));
        }
        let variant = match &o.variant {
            None => kind.default_variant(),
            Some(name) => Variant::parse(name)
                .ok_or_else(|| JsError::new(&format!("no scene variant named `{name}`")))?,
        };
        for (name, v) in [
            ("occluder_scale", o.occluder_scale),
            ("pull_scale", o.pull_scale),
        ] {
            if !(0.0..=MAX_KNOB_SCALE).contains(&v) {
                return Err(JsError::new(&format!(
                    "{name} must be in [0, {MAX_KNOB_SCALE}], not {v}"
                )));
            }
        }
        let mut render = variant.render();
        if let Some(c) = &o.rope_colour {
            render.rope_color = ROPE_COLOURS
                .iter()
                .find(|(n, _)| n == c)
                .ok_or_else(|| JsError::new(&format!("no rope colour named `{c}`")))?
                .1;
        }
        let knobs = SceneKnobs {
            occluder_scale: o.occluder_scale,
            pull_scale: o.pull_scale,
        };
        let scenario = Scenario::with_knobs(kind, o.frames, o.seed, render, variant.rope(), knobs);
        let writer = SyntheticWriter::new(scenario);
        let mut files = MemorySource::new(kind.name());
        for (path, bytes) in writer.header().map_err(js_err)? {
            files.insert(&path, bytes);
        }
        Ok(Self {
            writer,
            files,
            total: o.frames,
        })
    }

    /// Frames the scene will have.
    pub fn total(&self) -> u32 {
        self.total as u32
    }

    /// Renders up to `count` more frames; returns the frames written in all.
    pub fn render(&mut self, count: u32) -> Result<u32, JsError> {
        for _ in 0..count {
            let Some(files) = self.writer.next_frame().map_err(js_err)? else {
                break;
            };
            for (path, bytes) in files {
                self.files.insert(&path, bytes);
            }
        }
        if self.writer.written() == self.total {
            let (path, bytes) = self.writer.groundtruth().map_err(js_err)?;
            self.files.insert(&path, bytes);
        }
        Ok(self.writer.written() as u32)
    }

    /// Every file path written (as `Archive.names`).
    pub fn names(&self) -> Vec<String> {
        self.files.paths().map(str::to_string).collect()
    }

    /// The bytes of one file (as `Archive.read`).
    pub fn read(&self, path: &str) -> Result<Vec<u8>, JsError> {
        self.files.read(path).map_err(js_err)
    }
}
