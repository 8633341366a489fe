//! # mapc-rl (being written)
