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
