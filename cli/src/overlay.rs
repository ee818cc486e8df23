//! `upetrack overlay`: draws a frame with the ground truth (green), the
//! tracked nodes (red visible, yellow hidden; with several ropes each
//! rope's visible nodes in its own colour) and the curve through them, to
//! look at what the tracker did.

use upetrack::math::Vec3;
use upetrack_io::result::TrackResult;
use upetrack_io::write::{encode_rgb_png, write_file};

use crate::args::OverlayArgs;
use crate::{open_sequence, CliError};

/// Visible nodes of rope `k` of several (the page's colours): red, blue,
/// green, then on.
const ROPE_VISIBLE: [[u8; 3]; 4] = [[230, 30, 30], [32, 96, 255], [16, 176, 64], [192, 64, 224]];

fn put(rgb: &mut [u8], w: i64, h: i64, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && x < w && y < h {
        let i = ((y * w + x) * 3) as usize;
        rgb[i..i + 3].copy_from_slice(&c);
    }
}

fn line(rgb: &mut [u8], w: i64, h: i64, a: (f64, f64), b: (f64, f64), c: [u8; 3]) {
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as i64).clamp(1, 10_000);
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        put(rgb, w, h, x.round() as i64, y.round() as i64, c);
    }
}

fn disc(rgb: &mut [u8], w: i64, h: i64, p: (f64, f64), r: i64, c: [u8; 3]) {
    for dy in -r..=r {
        for dx in -r..=r {
            if dx * dx + dy * dy <= r * r {
                put(
                    rgb,
                    w,
                    h,
                    p.0.round() as i64 + dx,
                    p.1.round() as i64 + dy,
                    c,
                );
            }
        }
    }
}

/// `upetrack overlay <sequence> <result.json> <frame> <out.png>`.
pub fn cmd_overlay(args: &OverlayArgs) -> Result<(), CliError> {
    let seq = open_sequence(&args.sequence, &args.recording)?;
    let result: TrackResult = upetrack_io::result::read_result(&args.result)?;
    let index = args.frame;
    if index >= seq.len() {
        return Err(CliError::input(format!(
            "{}: frame {index} is past the last frame ({} frames)",
            args.sequence,
            seq.len()
        )));
    }
    let decoded = seq.frame(index)?;
    let (w, h) = (decoded.width as i64, decoded.height as i64);
    let mut rgb = decoded.color;
    if args.depth {
        rgb = upetrack_io::display::depth_to_rgb(&decoded.depth);
    }
    for r in seq.occlusions_at(index) {
        if let Some((x0, x1, y0, y1)) = r.clip(decoded.width, decoded.height) {
            for y in y0..y1 {
                for x in x0..x1 {
                    put(&mut rgb, w, h, x as i64, y as i64, [0, 0, 0]);
                }
            }
        }
    }
    let cam = seq.camera;
    let project = |p: &Vec3| cam.project(p).map(|q| (q.x, q.y));
    // Every rope's truth and nodes (one rope: the sequence's and the
    // result's frames); each rope's visible nodes in its own colour.
    for k in 0..result.rope_count().max(seq.ropes.len()) {
        let truth = seq.ropes.get(k).map(|r| &r.groundtruth);
        if let Some(Some(gt)) = truth.and_then(|t| t.get(index)) {
            let pts: Vec<(f64, f64)> = gt.iter().filter_map(project).collect();
            for s in pts.windows(2) {
                line(&mut rgb, w, h, s[0], s[1], [0, 220, 0]);
            }
        }
        let Some(rope) = result.rope(k) else {
            continue;
        };
        let Some(rec) = rope.frames.iter().find(|f| f.frame == index) else {
            continue;
        };
        let pts: Vec<Option<(f64, f64)>> = rec
            .nodes
            .iter()
            .map(|p| project(&Vec3::new(p[0], p[1], p[2])))
            .collect();
        for s in pts.windows(2) {
            if let (Some(a), Some(b)) = (s[0], s[1]) {
                line(&mut rgb, w, h, a, b, [255, 255, 255]);
            }
        }
        let visible = ROPE_VISIBLE[k % ROPE_VISIBLE.len()];
        for (p, vis) in pts.iter().zip(&rec.visible) {
            if let Some(p) = p {
                disc(
                    &mut rgb,
                    w,
                    h,
                    *p,
                    3,
                    if *vis { visible } else { [255, 210, 0] },
                );
            }
        }
    }
    write_file(
        &args.out,
        &encode_rgb_png(decoded.width, decoded.height, &rgb)?,
    )?;
    Ok(())
}
