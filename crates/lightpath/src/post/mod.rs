//! Post-processing of rendered EXRs: additive compositing (`comp`), merging sample
//! ranges (`merge`), checking that partitions sum to their whole (`partitions`) and
//! denoising every AOV with the partitions kept (`denoise`).
//! Each reads the structured header attributes of `aov::naming`, never definitions' prose.

pub mod comp;
pub mod cryptomatte;
pub mod denoise;
pub mod diff;
pub mod merge;
#[cfg(feature = "denoise")]
mod oidn;
pub mod partitions;

pub use comp::{aov_planes, evaluate, gain_terms, parse, Term};
pub use merge::merge;
pub use partitions::{check_partitions, PartitionCheck};
