//! [`SplitMix64`], the seeded generator behind every random choice here:
//! mint-core's, shared with mint-mesh, so a seed means the same mesh forever.

pub use mint_core::rng::SplitMix64;
