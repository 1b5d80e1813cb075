pub mod disc;
pub mod netgen;
