//! The steps after the clustering, one module each: M merges clusters lying inside a
//! cluster of another label ([`merge_nodes`], ALGORITHM.md §5.4), R removes clusters cut
//! off from the body tree ([`remove_nodes`], §5.5, with [`restore_bridged`]), N relabels
//! noise ([`reassign_noise`] and its votes, §5.6), S smooths the labels after them
//! ([`smooth_labels`]). Each is a plain function.

mod cells;
mod merge;
mod noise;
mod remove;
mod smooth;

pub use merge::merge_nodes;
pub(crate) use noise::{NoiseNearest, quantile};
pub use noise::{
    Vote, doubtful_as_unknown, reassign_doubted_wide, reassign_noise, reassign_noise_weighted,
};
pub use remove::{remove_nodes, restore_bridged};
pub use smooth::smooth_labels;
