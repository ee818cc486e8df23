//! Camera recordings (.bag) opened in the page's worker: the file is read in
//! slices (`Blob.slice` with `FileReaderSync`), never whole, through the same
//! reader the command uses.

use serde::Serialize;
use upetrack_io::recorded::{recording_sequence, OpenRecording};
use upetrack_io::sequence::{DloConfig, Sequence};
use upetrack_io::source::MemorySource;
use upetrack_recordings::{ByteSource, RecordingError, RecordingOptions};
use wasm_bindgen::prelude::*;

use crate::{js_err, sequence_info, DecodedFrame};

/// Bytes read at once for small reads (record headers, index entries): one
/// slice serves the few reads around one place; larger blocks would read
/// past the next chunk header for nothing.
pub const READ_BLOCK_BYTES: usize = 16 * 1024;

/// A `Blob` (a picked or dropped `File`) as random-access bytes.
struct BlobBytes {
    blob: web_sys::Blob,
    reader: web_sys::FileReaderSync,
    len: u64,
    /// The last block read: its offset and bytes.
    block: (u64, Vec<u8>),
    /// Told `(offset, length)` as reading moves on, for a progress bar.
    progress: Option<js_sys::Function>,
    reported: u64,
}

fn io_error(what: &str, e: JsValue) -> RecordingError {
    RecordingError::Io {
        what: what.to_string(),
        source: std::io::Error::other(format!("{e:?}")),
    }
}

impl BlobBytes {
    /// Bytes `start..start + out.len()` of the file, copied once into `out`.
    fn slice_into(&self, start: u64, out: &mut [u8]) -> Result<(), RecordingError> {
        let end = start + out.len() as u64;
        let part = self
            .blob
            .slice_with_f64_and_f64(start as f64, end as f64)
            .map_err(|e| io_error("Blob.slice", e))?;
        let buffer = self
            .reader
            .read_as_array_buffer(&part)
            .map_err(|e| io_error("FileReaderSync", e))?;
        let view = js_sys::Uint8Array::new(&buffer);
        if view.length() as usize != out.len() {
            return Err(io_error("FileReaderSync", JsValue::from_str("short read")));
        }
        view.copy_to(out);
        Ok(())
    }
}

impl ByteSource for BlobBytes {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        upetrack_recordings::bytes::check_range(self.len, offset, buf.len())?;
        let end = offset + buf.len() as u64;
        if let Some(f) = &self.progress {
            // About a hundred reports over the file, not one per read.
            if offset.abs_diff(self.reported) > self.len / 100 {
                self.reported = offset;
                let _ = f.call2(
                    &JsValue::NULL,
                    &JsValue::from_f64(offset as f64),
                    &JsValue::from_f64(self.len as f64),
                );
            }
        }
        if buf.len() >= READ_BLOCK_BYTES {
            return self.slice_into(offset, buf);
        }
        let (start, bytes) = &self.block;
        let cached = offset >= *start && end <= start + bytes.len() as u64;
        if !cached {
            let block_end = (offset + READ_BLOCK_BYTES as u64).min(self.len);
            let mut block = vec![0u8; (block_end - offset) as usize];
            self.slice_into(offset, &mut block)?;
            self.block = (offset, block);
        }
        let (start, bytes) = &self.block;
        let from = (offset - start) as usize;
        buf.copy_from_slice(&bytes[from..from + buf.len()]);
        Ok(())
    }
}

/// A recording opened in the worker: its frames decoded (and depth aligned)
/// on demand.
#[wasm_bindgen]
pub struct Recording {
    seq: Sequence<MemorySource>,
}

#[wasm_bindgen]
impl Recording {
    /// Opens `file` (a `File` or `Blob`; `name` for messages), configured by
    /// `dlo` (the text of a dlo.json, or null). `progress(offset, length)` is
    /// called while the index is read. Worker only (`FileReaderSync`).
    #[wasm_bindgen(constructor)]
    pub fn new(
        file: web_sys::Blob,
        name: &str,
        dlo: Option<String>,
        progress: Option<js_sys::Function>,
    ) -> Result<Recording, JsError> {
        let reader = web_sys::FileReaderSync::new()
            .map_err(|_| JsError::new("recordings open in a worker (FileReaderSync)"))?;
        let bytes = BlobBytes {
            len: file.size() as u64,
            blob: file,
            reader,
            block: (0, Vec::new()),
            progress,
            reported: 0,
        };
        let rec = OpenRecording::from_source(Box::new(bytes), name, &RecordingOptions::default())
            .map_err(js_err)?;
        let mut config = MemorySource::new(name);
        if let Some(text) = dlo {
            // The page is given no ground truth beside a recording: a
            // dlo.json that names one is read without it.
            let mut dlo = DloConfig::parse(text.as_bytes(), "dlo.json").map_err(js_err)?;
            dlo.groundtruth = None;
            let bytes = serde_json::to_vec(&dlo).map_err(js_err)?;
            config.insert("dlo.json", bytes);
        }
        let seq = recording_sequence(config, rec).map_err(js_err)?;
        Ok(Self { seq })
    }

    /// `{camera, depth_scale, fps, hsv, occlusions, color_files, depth_files,
    /// groundtruth}`, as `readSequenceInfo` gives for a folder.
    pub fn info(&self) -> Result<JsValue, JsError> {
        sequence_info(&self.seq)
    }

    /// Streams, pairing and warnings, as `upetrack info --json` prints them.
    pub fn details(&self) -> Result<JsValue, JsError> {
        let info = self.seq.recording_info();
        info.serialize(&serde_wasm_bindgen::Serializer::json_compatible())
            .map_err(js_err)
    }

    /// Frame `index`: colour and depth aligned to it.
    pub fn frame(&self, index: usize) -> Result<DecodedFrame, JsError> {
        let f = self.seq.frame(index).map_err(js_err)?;
        Ok(DecodedFrame {
            width: f.width,
            height: f.height,
            rgb: f.color,
            rgba: None,
            depth: f.depth,
        })
    }
}
