pub mod obs;
pub mod merge;
