pub mod distributed;
pub mod merge;
pub mod obs;
