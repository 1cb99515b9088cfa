//! `compiler-dag`: instruction scheduling for low switching energy, as an SOP.
//!
//! The public compiler instances of the SOP literature come from a compiler scheduling the
//! instructions of one basic block so that consecutive instruction words differ in as few
//! bits as possible (switching cost = Hamming distance of the encodings), subject to the
//! block's data dependence graph. This generator builds such blocks itself: a straight-line
//! program of `n` instructions with 32-bit words laid out like ARM's data-processing,
//! multiply and load/store formats (condition, opcode, register and immediate fields), and
//! the dependences a scheduler must respect — read after write, write after read and write
//! after write on registers, the condition flags and memory. The dependence graph is sparse
//! and not transitively closed; costs are integers in 0..=32 and symmetric.

use super::{n_spec, sop_shaped};
use crate::error::{Error, Result};
use crate::model::Instance;
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeSet;

/// Parameters.
pub static SPECS: &[ParamSpec] = &[
    n_spec("200", super::MAX_N),
    ParamSpec {
        name: "regs",
        default: "13",
        kind: ParamKind::int(2, 16),
        help: "general registers the block uses (2..=16)",
    },
    ParamSpec {
        name: "chains",
        default: "3",
        kind: ParamKind::int(1, 16),
        help: "independent computations interleaved in the block, each with its own registers (1..=regs)",
    },
    ParamSpec {
        name: "mem",
        default: "0.3",
        kind: ParamKind::float(0.0, 1.0),
        help: "share of loads and stores (a third of them stores)",
    },
];

/// What an instruction reads and writes, and its word.
struct Insn {
    word: u32,
    reads: Vec<usize>,
    writes: Vec<usize>,
}

/// Pseudo-resources after the registers: the flags, then memory words (a base register and
/// a word offset; accesses through different bases or offsets are taken not to alias).
const FLAGS: usize = 16;
const MEMORY: usize = 17;
/// Resources in all: registers, flags, 16 × 16 memory words.
const RESOURCES: usize = MEMORY + 256;

struct Gen<'a> {
    rng: &'a mut ChaCha8Rng,
    regs: u32,
    chains: u32,
    /// the chain the current instruction belongs to
    chain: u32,
    /// registers used last, per chain
    recent: Vec<Vec<u32>>,
}

impl Gen<'_> {
    /// A register of the current chain (registers r with r mod chains = chain), often one of
    /// the last few the chain used (blocks reuse their values).
    fn reg(&mut self) -> u32 {
        let recent = &self.recent[self.chain as usize];
        if !recent.is_empty() && self.rng.random_bool(0.5) {
            let k = self.rng.random_range(0..recent.len());
            return recent[k];
        }
        let own = (self.regs - self.chain).div_ceil(self.chains);
        self.chain + self.chains * self.rng.random_range(0..own)
    }
    fn used(&mut self, r: u32) {
        let recent = &mut self.recent[self.chain as usize];
        recent.push(r);
        if recent.len() > 4 {
            recent.remove(0);
        }
    }
    fn cond(&mut self) -> (u32, bool) {
        if self.rng.random_bool(0.9) {
            (0b1110, false)
        } else {
            (self.rng.random_range(0..14), true)
        }
    }
    fn insn(&mut self, mem: f64) -> Insn {
        self.chain = self.rng.random_range(0..self.chains);
        let (cond, conditional) = self.cond();
        let mut reads = Vec::new();
        let mut writes = Vec::new();
        if conditional {
            reads.push(FLAGS);
        }
        let word = if self.rng.random_bool(mem) {
            // LDR / STR rd, [rn, #imm12]
            let store = self.rng.random_bool(1.0 / 3.0);
            let (rn, rd) = (self.reg(), self.reg());
            let word = self.rng.random_range(0..16u32);
            let off = word * 4;
            let loc = MEMORY + (rn * 16 + word) as usize;
            reads.push(rn as usize);
            if store {
                reads.push(rd as usize);
                writes.push(loc);
            } else {
                reads.push(loc);
                writes.push(rd as usize);
            }
            self.used(rn);
            self.used(rd);
            let (p, u, l) = (1u32, 1u32, u32::from(!store));
            cond << 28 | 0b01 << 26 | p << 24 | u << 23 | l << 20 | rn << 16 | rd << 12 | off
        } else if self.rng.random_bool(0.07) {
            // MUL rd, rm, rs
            let (rd, rm, rs) = (self.reg(), self.reg(), self.reg());
            reads.extend([rm as usize, rs as usize]);
            writes.push(rd as usize);
            self.used(rd);
            cond << 28 | rd << 16 | rs << 8 | 0b1001 << 4 | rm
        } else {
            // data processing: opcode rd, rn, operand2
            // mostly ADD, SUB, MOV, AND, ORR, EOR, RSB, BIC; a compare now and then
            let opcode = if self.rng.random_bool(0.08) {
                0b1010 // CMP
            } else {
                const COMMON: [u32; 8] = [
                    0b0100, 0b0010, 0b1101, 0b0000, 0b1100, 0b0001, 0b0011, 0b1110,
                ];
                COMMON[self.rng.random_range(0..COMMON.len())]
            };
            let compare = (0b1000..=0b1011).contains(&opcode); // TST TEQ CMP CMN
            let moves = opcode == 0b1101 || opcode == 0b1111; // MOV MVN ignore rn
            let s = u32::from(compare || self.rng.random_bool(0.03));
            let imm = self.rng.random_bool(0.5);
            let rn = if moves { 0 } else { self.reg() };
            let rd = if compare { 0 } else { self.reg() };
            if !moves {
                reads.push(rn as usize);
                self.used(rn);
            }
            if !compare {
                writes.push(rd as usize);
                self.used(rd);
            }
            if s == 1 {
                writes.push(FLAGS);
            }
            let op2 = if imm {
                self.rng.random_range(0..16u32) << 8 | self.rng.random_range(0..32u32)
            } else {
                let rm = self.reg();
                reads.push(rm as usize);
                self.used(rm);
                let shift = if self.rng.random_bool(0.8) {
                    0
                } else {
                    self.rng.random_range(0..256u32)
                };
                shift << 4 | rm
            };
            cond << 28 | u32::from(imm) << 25 | opcode << 21 | s << 20 | rn << 16 | rd << 12 | op2
        };
        Insn {
            word,
            reads,
            writes,
        }
    }
}

/// Dependences of a straight-line block: read after write, write after read, write after
/// write, on every register, the flags and memory.
fn dependences(block: &[Insn]) -> Vec<(usize, usize)> {
    let mut last_write: Vec<Option<usize>> = vec![None; RESOURCES];
    let mut reads_since: Vec<Vec<usize>> = vec![Vec::new(); RESOURCES];
    let mut edges = BTreeSet::new();
    for (i, ins) in block.iter().enumerate() {
        for &r in &ins.reads {
            if let Some(w) = last_write[r] {
                edges.insert((w, i));
            }
        }
        for &r in &ins.writes {
            if let Some(w) = last_write[r] {
                edges.insert((w, i));
            }
            for &rd in &reads_since[r] {
                if rd != i {
                    edges.insert((rd, i));
                }
            }
        }
        for &r in &ins.reads {
            reads_since[r].push(i);
        }
        for &r in &ins.writes {
            last_write[r] = Some(i);
            reads_since[r].clear();
        }
    }
    edges.into_iter().collect()
}

/// Checks the parameters together (`chains` ≤ `regs`); the number of cells.
pub fn check(p: &Params) -> Result<u64> {
    let (regs, chains) = (p.int("regs"), p.int("chains"));
    if chains > regs {
        return Err(Error::Param(format!(
            "compiler-dag: chains must lie in 1..=regs ({regs}), got {chains}"
        )));
    }
    Ok(p.int("n") + 2)
}

/// Generates a `compiler-dag` instance.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    check(p)?;
    let n = p.int("n") as usize;
    let regs = p.int("regs");
    let mem = p.float("mem");
    let chains = p.int("chains");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut g = Gen {
        rng: &mut rng,
        regs: regs as u32,
        chains: chains as u32,
        chain: 0,
        recent: vec![Vec::new(); chains as usize],
    };
    let block: Vec<Insn> = (0..n).map(|_| g.insn(mem)).collect();
    let edges = dependences(&block);
    let words: Vec<u32> = block.iter().map(|i| i.word).collect();
    let name = format!("compiler-dag-n{n}-s{seed}");
    Ok(sop_shaped(
        name,
        &vec![1; n],
        |u, v| (words[u] ^ words[v]).count_ones() as f64,
        &edges,
    ))
}
