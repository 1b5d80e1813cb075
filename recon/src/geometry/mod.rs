//! Small fixed-size geometry: a plain `Vec3` and triangle helpers used by every operator.

mod closest_point;
mod triangle;
mod triangle_bvh;
mod vec3;

pub use closest_point::{closest_point_on_segment, closest_point_on_triangle};
pub use triangle::{
    cot_of_angle_between, is_degenerate_triangle, triangle_angles, triangle_area, triangle_normal,
};
pub use triangle_bvh::{ClosestHit, TriangleBvh, LEAF_SIZE};
pub use vec3::{bounding_box, Vec3};
