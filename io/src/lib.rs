//! Sequences in the contract's layout (`docs/sequence-format.md`): reading
//! them from a folder or from files held in memory, decoding colour and
//! depth images, writing them, the result JSON, and evaluation statistics.
//! A camera recording (`.bag`) is read as a sequence through [`recorded`].
#![warn(missing_docs)]

pub mod archive;
pub mod capped;
pub mod decode;
pub mod display;
pub mod error;
pub mod eval;
pub mod export;
pub mod open;
pub mod params_file;
pub mod params_schema;
pub mod recorded;
pub mod recording_info;
pub mod result;
pub mod ropes;
pub mod run;
pub mod sequence;
pub mod source;
pub mod synthetic;
pub mod synthetic_several;
pub mod write;

pub use error::SequenceError;
pub use sequence::{DecodedFrame, Sequence};
pub use source::{FolderSource, MemorySource, Source};
