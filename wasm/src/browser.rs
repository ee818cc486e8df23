//! Colour decoded by the browser's own image decoder: the page's worker
//! turns a JPEG or PNG into an `ImageBitmap` (`createImageBitmap`, off the
//! worker's thread), and its pixels are read back here through an
//! `OffscreenCanvas`. Depth stays with the 16-bit PNG decoder in wasm: a
//! canvas holds 8 bits per channel.

use std::cell::RefCell;

use upetrack_io::decode::decode_depth;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;
use web_sys::{ImageBitmap, OffscreenCanvas, OffscreenCanvasRenderingContext2d};

use crate::{js_err, DecodedFrame};

thread_local! {
    /// One canvas, reused while frames keep their size.
    static CANVAS: RefCell<Option<(OffscreenCanvas, OffscreenCanvasRenderingContext2d)>> =
        const { RefCell::new(None) };
}

fn context(width: u32, height: u32) -> Result<OffscreenCanvasRenderingContext2d, String> {
    CANVAS.with(|cell| {
        let mut slot = cell.borrow_mut();
        if let Some((canvas, ctx)) = slot.as_ref() {
            if canvas.width() == width && canvas.height() == height {
                return Ok(ctx.clone());
            }
        }
        let canvas =
            OffscreenCanvas::new(width, height).map_err(|e| js_value_err("OffscreenCanvas", e))?;
        // `willReadFrequently` keeps the canvas in memory the CPU reads.
        let options = js_sys::Object::new();
        js_sys::Reflect::set(&options, &"willReadFrequently".into(), &JsValue::TRUE)
            .map_err(|e| js_value_err("canvas options", e))?;
        let ctx = canvas
            .get_context_with_context_options("2d", &options)
            .map_err(|e| js_value_err("OffscreenCanvas.getContext", e))?
            .ok_or("this browser gives no 2d context for an OffscreenCanvas")?
            .dyn_into::<OffscreenCanvasRenderingContext2d>()
            .map_err(|_| "OffscreenCanvas.getContext('2d') is not a 2d context")?;
        *slot = Some((canvas, ctx.clone()));
        Ok(ctx)
    })
}

fn js_value_err(what: &str, e: JsValue) -> String {
    format!(
        "{what}: {}",
        e.as_string().unwrap_or_else(|| format!("{e:?}"))
    )
}

/// The RGBA8 pixels of a decoded bitmap.
fn bitmap_rgba(bitmap: &ImageBitmap) -> Result<(u32, u32, Vec<u8>), String> {
    let (width, height) = (bitmap.width(), bitmap.height());
    if width == 0 || height == 0 {
        return Err("the colour image is empty".into());
    }
    let ctx = context(width, height)?;
    ctx.draw_image_with_image_bitmap(bitmap, 0.0, 0.0)
        .map_err(|e| js_value_err("drawImage", e))?;
    let data = ctx
        .get_image_data(0.0, 0.0, f64::from(width), f64::from(height))
        .map_err(|e| js_value_err("getImageData", e))?
        .data();
    Ok((width, height, data.0))
}

/// A frame whose colour the browser decoded into `rgba` (RGBA8, `width` x
/// `height`, rows packed: `ImageDecoder` and `VideoFrame.copyTo`) and whose
/// depth file (16-bit PNG) is decoded here.
#[wasm_bindgen(js_name = decodeRgbaFrame)]
pub fn decode_rgba_frame(
    rgba: &[u8],
    width: u32,
    height: u32,
    color_name: &str,
    depth: &[u8],
    depth_name: &str,
) -> Result<DecodedFrame, JsError> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected || width == 0 || height == 0 {
        return Err(JsError::new(&format!(
            "{color_name}: {} bytes of RGBA for {width}x{height}",
            rgba.len()
        )));
    }
    let d = decode_depth(depth, depth_name).map_err(js_err)?;
    DecodedFrame::from_rgba(width, height, rgba.to_vec(), d, color_name, depth_name)
}

/// A frame whose colour the browser decoded (`bitmap`, from
/// `createImageBitmap(blob, {colorSpaceConversion: 'none', premultiplyAlpha: 'none'})`)
/// and whose depth file (16-bit PNG) is decoded here; the names are used in
/// error messages. Both must have the same size.
#[wasm_bindgen(js_name = decodeBitmapFrame)]
pub fn decode_bitmap_frame(
    bitmap: &ImageBitmap,
    color_name: &str,
    depth: &[u8],
    depth_name: &str,
) -> Result<DecodedFrame, JsError> {
    let (width, height, rgba) =
        bitmap_rgba(bitmap).map_err(|e| JsError::new(&format!("{color_name}: {e}")))?;
    let d = decode_depth(depth, depth_name).map_err(js_err)?;
    DecodedFrame::from_rgba(width, height, rgba, d, color_name, depth_name)
}

/// Depth given to every pixel of a colour-only frame (a webcam's), metres:
/// the table distance of the bundled scenes, so that lengths in pixels, and
/// with them the default parameters, mean what they mean there.
pub const COLOUR_ONLY_DEPTH_M: f64 = 0.6;

/// Depth units of a colour-only frame, metres.
const COLOUR_ONLY_DEPTH_SCALE: f64 = 0.001;

/// Focal length of a colour-only camera at 640 pixels wide (the D435i's
/// colour camera), pixels; it scales with the width.
const COLOUR_ONLY_FOCAL_AT_640: f64 = 615.0;

/// The camera assumed for a colour-only stream of `width` x `height`
/// pixels, with the depth units of its frames: `{camera: {width, height,
/// fx, fy, cx, cy}, depth_scale}`; the D435i's colour field of view.
#[wasm_bindgen(js_name = colourOnlySetup)]
pub fn colour_only_setup(width: u32, height: u32) -> Result<JsValue, JsError> {
    #[derive(serde::Serialize)]
    struct Setup {
        camera: upetrack::CameraIntrinsics,
        depth_scale: f64,
    }
    let f = COLOUR_ONLY_FOCAL_AT_640 * f64::from(width) / 640.0;
    crate::to_js(&Setup {
        camera: upetrack::CameraIntrinsics {
            width,
            height,
            fx: f,
            fy: f,
            cx: f64::from(width) / 2.0,
            cy: f64::from(height) / 2.0,
        },
        depth_scale: COLOUR_ONLY_DEPTH_SCALE,
    })
}

/// A colour-only frame (a webcam's `ImageBitmap`) as a frame to track: the
/// depth of every pixel is [`COLOUR_ONLY_DEPTH_M`] (in units of 1 mm), so
/// the rope is tracked on a plane, that is, in the image.
#[wasm_bindgen(js_name = colourOnlyFrame)]
pub fn colour_only_frame(bitmap: &ImageBitmap) -> Result<DecodedFrame, JsError> {
    let (width, height, rgba) =
        bitmap_rgba(bitmap).map_err(|e| JsError::new(&format!("camera frame: {e}")))?;
    let units = (COLOUR_ONLY_DEPTH_M / COLOUR_ONLY_DEPTH_SCALE).round() as u16;
    let depth = upetrack_io::decode::DepthImage {
        width,
        height,
        data: vec![units; width as usize * height as usize],
    };
    DecodedFrame::from_rgba(width, height, rgba, depth, "camera frame", "camera frame")
}
