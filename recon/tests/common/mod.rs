pub mod disc;
