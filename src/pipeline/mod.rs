//! Pipelines from a file to a better file: groups in their required order → instance →
//! solver → keep the original where not worse → verify → write.

pub mod drawing;
