//! A scene of several ropes (`upetrack_synth::SeveralRopes`) written as
//! the contract's files: `dlo.json` lists the ropes (`ropes`), each with
//! its colour range and its own ground-truth file.

use upetrack_synth::SeveralRopes;

use crate::error::SequenceError;
use crate::ropes::RopeEntry;
use crate::sequence::{DloConfig, GroundTruthFile, IntrinsicsFile, RopeConfig, SegmentationConfig};
use crate::synthetic::{
    frame_files, truth_frame, SequenceFile, SYNTHETIC_DEPTH_SCALE, SYNTHETIC_FPS,
};
use crate::write::{compact_json_bytes, json_bytes};

/// Rope `name`'s ground-truth file.
pub fn groundtruth_file(name: &str) -> String {
    format!("groundtruth-{name}.json")
}

/// Writes every file of `scene` through `put` (with the ropes' lengths
/// and diameters in `dlo.json` when `rope_prior`; colour at JPEG
/// `quality`, 1..=100, clamped); returns the frame count.
pub fn write_several(
    mut scene: SeveralRopes,
    rope_prior: bool,
    quality: u8,
    put: &mut dyn FnMut(SequenceFile) -> Result<(), SequenceError>,
) -> Result<usize, SequenceError> {
    let camera = scene.camera();
    let ropes: Vec<RopeEntry> = (0..scene.ropes.len())
        .map(|k| RopeEntry {
            name: Some(scene.names[k].clone()),
            segmentation: Some(SegmentationConfig::of(&scene.hsv(k))),
            rope: rope_prior.then_some(RopeConfig {
                length_m: Some(scene.ropes[k].settings.length),
                diameter_m: Some(scene.ropes[k].settings.thickness),
            }),
            groundtruth: Some(groundtruth_file(&scene.names[k])),
            hint: scene.hint(k).map(|h| [h.x, h.y]),
        })
        .collect();
    let dlo = DloConfig {
        depth_scale: Some(SYNTHETIC_DEPTH_SCALE),
        fps: Some(SYNTHETIC_FPS),
        segmentation: ropes.first().and_then(|r| r.segmentation.clone()),
        groundtruth: ropes.first().and_then(|r| r.groundtruth.clone()),
        ropes,
        ..DloConfig::default()
    };
    let intrinsics = IntrinsicsFile::from_camera(&camera);
    put((
        "camera_intrinsic.json".into(),
        json_bytes("camera_intrinsic.json", &intrinsics)?,
    ))?;
    put(("dlo.json".into(), json_bytes("dlo.json", &dlo)?))?;
    let mut truths = vec![GroundTruthFile::default(); scene.ropes.len()];
    let mut written = 0;
    while let Some(f) = scene.next_frame() {
        for file in frame_files(f.index, &camera, &f.rgb, &f.depth, quality.clamp(1, 100))? {
            put(file)?;
        }
        for (truth, rope) in truths.iter_mut().zip(f.ropes) {
            truth
                .frames
                .push(truth_frame(f.index, &rope.points, rope.occluded));
        }
        written += 1;
    }
    for (truth, name) in truths.iter().zip(&scene.names) {
        let path = groundtruth_file(name);
        let bytes = compact_json_bytes(&path, truth)?;
        put((path, bytes))?;
    }
    Ok(written)
}
