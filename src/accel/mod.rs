//! Acceleration structures built on the host and uploaded as flat arrays.

pub mod bvh;
pub mod wide;

pub use bvh::{build_bvh, build_bvh_with_leaves, Bvh, BvhError};
