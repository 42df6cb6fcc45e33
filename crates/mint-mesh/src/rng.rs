//! The seeded generator of the distance sampler: mint-core's [`SplitMix64`],
//! re-exported so that the sampler and the generators share one algorithm.

pub use mint_core::rng::{mix64, SplitMix64};
