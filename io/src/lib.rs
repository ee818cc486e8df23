//! Sequences in the contract's layout (`docs/sequence-format.md`): reading
//! them from a folder or from files held in memory, decoding colour and
//! depth images, writing them, the result JSON, and evaluation statistics.
#![warn(missing_docs)]

pub mod archive;
pub mod decode;
pub mod display;
pub mod error;
pub mod eval;
pub mod open;
pub mod params_file;
pub mod result;
pub mod run;
pub mod sequence;
pub mod source;
pub mod write;

pub use error::SequenceError;
pub use sequence::{DecodedFrame, Sequence};
pub use source::{FolderSource, MemorySource, Source};
