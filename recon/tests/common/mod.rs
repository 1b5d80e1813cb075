pub mod disc;
pub mod netgen;
pub mod systems;
