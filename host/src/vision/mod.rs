//! Image processing on the hot path: blob detection on 8-bit infrared frames (issue 5 item 1).

pub mod blobs;

pub use blobs::{
    principal_axis, BackgroundModel, Blob, BlobConfig, BlobDetector, GrayImage, ImageError, Rect,
    SearchRegion,
};
