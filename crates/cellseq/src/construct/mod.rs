//! Construction heuristics: library functions that build one feasible sequence from scratch,
//! counting their arc evaluations through a callback. The solvers call them (`greedy`,
//! `greedy-edge` and `insertion` are thin registry entries over them; `local-search`, `ils`
//! and the others start from them).

pub mod edge;
pub mod greedy;
pub mod insertion;
