pub mod merge;
pub mod obs;
