//! Small fixed-size geometry: a plain `Vec3` and triangle helpers used by every operator.

mod triangle;
mod vec3;

pub use triangle::{
    cot_of_angle_between, is_degenerate_triangle, triangle_angles, triangle_area, triangle_normal,
};
pub use vec3::Vec3;
