//! cellseq-programs: real machine programs and drawings for [`cellseq`] — G-code, SVG and DXF.
//!
//! The codecs ([`gcode`], [`svg`], [`dxf`], and [`drawing`], the model both drawing readers
//! produce) read real programs, extract a [`cellseq::model::Instance`] from them and write the
//! program back in a new order; they run no solver. The [`optimize`] pipeline does: groups in their
//! required order → instance → solver → the original order kept where it is not worse → verify
//! → write atomically; [`job`] is that pipeline in one call, from a file or text to the new
//! text and the report `cellseq optimize --json` prints.

// No unsafe code.
#![forbid(unsafe_code)]
// Every public item has a doc comment (CI turns this warning into an error).
#![warn(missing_docs)]
// Index loops are the clearest form for the geometry and interpreter code here.
#![allow(clippy::needless_range_loop)]

pub mod drawing;
pub mod dxf;
pub mod gcode;
pub mod job;
pub mod optimize;
pub mod svg;
