//! Readers and writers of machine programs and drawings (G-code).
//!
//! Unlike [`crate::formats`] (instance files), these modules read real programs, extract an
//! [`crate::model::Instance`] from them and write the program back in a new order.

pub mod drawing;
pub mod dxf;
pub mod gcode;
pub mod svg;
