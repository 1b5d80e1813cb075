//! Stereo rig calibration from chessboard views with OpenCV (Zhang's method; thesis ref. [113]):
//! corners per view (`findChessboardCorners` + `cornerSubPix`), each camera's intrinsics and distortion
//! (`calibrateCamera`), then the right camera's pose in the left camera's frame (`stereoCalibrate` with the
//! intrinsics fixed). RMS reprojection errors are reported in pixels. The thesis redoes this before every session.

use std::path::{Path, PathBuf};

use opencv::core::{self, Mat, Point2f, Point3f, Size, TermCriteria, Vector};
use opencv::prelude::*;
use opencv::{calib3d, imgcodecs, imgproc};

/// Errors of the calibration.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// OpenCV reported an error.
    #[error("OpenCV: {0}")]
    OpenCv(#[from] opencv::Error),
    /// An image could not be read.
    #[error("cannot read image {0}")]
    Image(PathBuf),
    /// Images of one camera differ in size.
    #[error("image {path} is {got:?}, the others are {expected:?}")]
    SizeMismatch {
        /// The odd image.
        path: PathBuf,
        /// Its size.
        got: (i32, i32),
        /// The size of the first image.
        expected: (i32, i32),
    },
    /// Too few views in which the board was found in both cameras.
    #[error("the chessboard was found in both images of only {found} view(s); at least {needed} are needed")]
    TooFewViews {
        /// Views usable.
        found: usize,
        /// Views needed.
        needed: usize,
    },
    /// No left/right image pairs in the directory.
    #[error("no image pairs (left_<id>.<ext> with right_<id>.<ext>) in {0}")]
    NoPairs(PathBuf),
    /// The directory could not be listed.
    #[error("cannot list {path}: {source}")]
    ListDir {
        /// The directory.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
}

/// The calibration target: a chessboard with `cols` x `rows` inner corners and square side `square_m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chessboard {
    /// Inner corners along a row.
    pub cols: i32,
    /// Inner corners along a column.
    pub rows: i32,
    /// Side of one square, metres.
    pub square_m: f64,
}

impl Chessboard {
    /// The board's inner corners in its own plane (z = 0), row by row, metres.
    fn object_points(&self) -> Vector<Point3f> {
        let s = self.square_m as f32;
        (0..self.rows)
            .flat_map(|r| {
                (0..self.cols).map(move |c| Point3f::new(c as f32 * s, r as f32 * s, 0.0))
            })
            .collect()
    }
}

/// One camera's intrinsics and distortion (the recordings' camera model) with the fit's RMS error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CameraCalibration {
    /// Intrinsics and OpenCV distortion (k1, k2, p1, p2, k3).
    pub model: fires_record::CameraModel,
    /// RMS reprojection error of this camera's calibration, pixels.
    pub rms_px: f64,
}

/// The calibrated rig: both cameras and the right camera's pose in the left (world) frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StereoCalibration {
    /// Left camera (defines the world frame).
    pub left: CameraCalibration,
    /// Right camera.
    pub right: CameraCalibration,
    /// Rotation left -> right, row-major (`x_right = R x_left + t`).
    pub rotation: [[f64; 3]; 3],
    /// Translation left -> right, metres.
    pub translation_m: [f64; 3],
    /// RMS reprojection error of the stereo fit, pixels.
    pub stereo_rms_px: f64,
    /// Views used (board found in both images).
    pub views: usize,
}

impl StereoCalibration {
    /// The rig as recordings store it: camera 0 (left) defines the world frame.
    pub fn to_rig(&self) -> fires_record::RigCalibration {
        use fires_record::{CalibratedCamera, Extrinsics};
        fires_record::RigCalibration {
            cameras: vec![
                CalibratedCamera {
                    intrinsics: self.left.model,
                    extrinsics: Extrinsics::IDENTITY,
                },
                CalibratedCamera {
                    intrinsics: self.right.model,
                    extrinsics: Extrinsics {
                        rotation: self.rotation,
                        translation_m: self.translation_m,
                    },
                },
            ],
        }
    }
}

/// An 8-bit grey image borrowed as rows of `width` bytes.
#[derive(Clone, Copy, Debug)]
pub struct GrayView<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row-major, `width * height` bytes.
    pub pixels: &'a [u8],
}

fn to_mat(img: GrayView<'_>) -> Result<Mat, CalibrationError> {
    let m = Mat::new_rows_cols_with_data(img.height as i32, img.width as i32, img.pixels)?;
    Ok(m.try_clone()?)
}

/// Finds the board's inner corners with sub-pixel refinement; `None` when the board is not (fully) visible.
pub fn find_corners(
    image: &Mat,
    board: &Chessboard,
) -> Result<Option<Vector<Point2f>>, CalibrationError> {
    let mut corners = Vector::<Point2f>::new();
    let flags = calib3d::CALIB_CB_ADAPTIVE_THRESH | calib3d::CALIB_CB_NORMALIZE_IMAGE;
    let pattern = Size::new(board.cols, board.rows);
    if !calib3d::find_chessboard_corners(image, pattern, &mut corners, flags)? {
        return Ok(None);
    }
    let criteria = TermCriteria::new(core::TermCriteria_COUNT + core::TermCriteria_EPS, 50, 1e-4)?;
    imgproc::corner_sub_pix(
        image,
        &mut corners,
        Size::new(5, 5),
        Size::new(-1, -1),
        criteria,
    )?;
    Ok(Some(corners))
}

/// Calibrates a stereo rig from image pairs of the same board pose (left, right).
pub fn calibrate_stereo(
    pairs: &[(GrayView<'_>, GrayView<'_>)],
    board: &Chessboard,
) -> Result<StereoCalibration, CalibrationError> {
    let mats = pairs
        .iter()
        .map(|(l, r)| Ok((to_mat(*l)?, to_mat(*r)?)))
        .collect::<Result<Vec<_>, CalibrationError>>()?;
    calibrate_stereo_mats(&mats, board)
}

/// Calibrates from `left_<id>.<ext>` / `right_<id>.<ext>` image files in `dir` (any format OpenCV reads).
pub fn calibrate_stereo_dir(
    dir: &Path,
    board: &Chessboard,
) -> Result<StereoCalibration, CalibrationError> {
    let mut mats = Vec::new();
    for (l, r) in image_pairs(dir)? {
        mats.push((read_gray(&l)?, read_gray(&r)?));
    }
    calibrate_stereo_mats(&mats, board)
}

/// The `left_*`/`right_*` pairs of `dir`, sorted by id.
pub fn image_pairs(dir: &Path) -> Result<Vec<(PathBuf, PathBuf)>, CalibrationError> {
    let list = std::fs::read_dir(dir).map_err(|source| CalibrationError::ListDir {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut pairs: Vec<(PathBuf, PathBuf)> = list
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?.to_owned();
            let rest = name.strip_prefix("left_")?;
            let right = p.with_file_name(format!("right_{rest}"));
            right.is_file().then_some((p, right))
        })
        .collect();
    pairs.sort();
    if pairs.is_empty() {
        return Err(CalibrationError::NoPairs(dir.to_path_buf()));
    }
    Ok(pairs)
}

fn read_gray(path: &Path) -> Result<Mat, CalibrationError> {
    let m = imgcodecs::imread(path, imgcodecs::IMREAD_GRAYSCALE)?;
    if m.empty() {
        return Err(CalibrationError::Image(path.to_path_buf()));
    }
    Ok(m)
}

/// Minimum views for a stable fit of 4 intrinsics + 5 distortion terms per camera.
const MIN_VIEWS: usize = 4;

fn calibrate_stereo_mats(
    mats: &[(Mat, Mat)],
    board: &Chessboard,
) -> Result<StereoCalibration, CalibrationError> {
    let (size_l, size_r) = match mats.first() {
        Some((l, r)) => (l.size()?, r.size()?),
        None => {
            return Err(CalibrationError::TooFewViews {
                found: 0,
                needed: MIN_VIEWS,
            })
        }
    };
    let mut object = Vector::<Vector<Point3f>>::new();
    let mut left = Vector::<Vector<Point2f>>::new();
    let mut right = Vector::<Vector<Point2f>>::new();
    for (l, r) in mats {
        check_size(l, size_l)?;
        check_size(r, size_r)?;
        if let (Some(cl), Some(cr)) = (find_corners(l, board)?, find_corners(r, board)?) {
            object.push(board.object_points());
            left.push(cl);
            right.push(cr);
        }
    }
    if object.len() < MIN_VIEWS {
        return Err(CalibrationError::TooFewViews {
            found: object.len(),
            needed: MIN_VIEWS,
        });
    }
    let (mut k_l, mut d_l, rms_l) = calibrate_one(&object, &left, size_l)?;
    let (mut k_r, mut d_r, rms_r) = calibrate_one(&object, &right, size_r)?;
    let (mut r, mut t, mut e, mut f) = (
        Mat::default(),
        Mat::default(),
        Mat::default(),
        Mat::default(),
    );
    let criteria = TermCriteria::new(core::TermCriteria_COUNT + core::TermCriteria_EPS, 100, 1e-9)?;
    let stereo_rms = calib3d::stereo_calibrate(
        &object,
        &left,
        &right,
        &mut k_l,
        &mut d_l,
        &mut k_r,
        &mut d_r,
        size_l,
        &mut r,
        &mut t,
        &mut e,
        &mut f,
        calib3d::CALIB_FIX_INTRINSIC,
        criteria,
    )?;
    Ok(StereoCalibration {
        left: camera_result(&k_l, &d_l, size_l, rms_l)?,
        right: camera_result(&k_r, &d_r, size_r, rms_r)?,
        rotation: mat3(&r)?,
        translation_m: [
            *t.at_2d::<f64>(0, 0)?,
            *t.at_2d::<f64>(1, 0)?,
            *t.at_2d::<f64>(2, 0)?,
        ],
        stereo_rms_px: stereo_rms,
        views: object.len(),
    })
}

fn check_size(m: &Mat, expected: Size) -> Result<(), CalibrationError> {
    let s = m.size()?;
    if s != expected {
        return Err(CalibrationError::SizeMismatch {
            path: PathBuf::from("<view>"),
            got: (s.width, s.height),
            expected: (expected.width, expected.height),
        });
    }
    Ok(())
}

fn calibrate_one(
    object: &Vector<Vector<Point3f>>,
    image: &Vector<Vector<Point2f>>,
    size: Size,
) -> Result<(Mat, Mat, f64), CalibrationError> {
    let mut k = Mat::default();
    let mut d = Mat::default();
    let (mut rvecs, mut tvecs) = (Vector::<Mat>::new(), Vector::<Mat>::new());
    let criteria = TermCriteria::new(core::TermCriteria_COUNT + core::TermCriteria_EPS, 100, 1e-9)?;
    // k3 stays zero: with the modest fields of view of the FIRES cameras (45° and the Minoru's) a board rarely
    // reaches the image corners, and a free r^6 term then overfits (k2 and k3 trade off wildly).
    let flags = calib3d::CALIB_FIX_K3;
    let rms = calib3d::calibrate_camera(
        object, image, size, &mut k, &mut d, &mut rvecs, &mut tvecs, flags, criteria,
    )?;
    Ok((k, d, rms))
}

fn camera_result(
    k: &Mat,
    d: &Mat,
    size: Size,
    rms: f64,
) -> Result<CameraCalibration, CalibrationError> {
    let dist = |i: i32| -> Result<f64, CalibrationError> { Ok(*d.at::<f64>(i)?) };
    Ok(CameraCalibration {
        model: fires_record::CameraModel {
            width: size.width.max(0) as u32,
            height: size.height.max(0) as u32,
            fx: *k.at_2d::<f64>(0, 0)?,
            fy: *k.at_2d::<f64>(1, 1)?,
            cx: *k.at_2d::<f64>(0, 2)?,
            cy: *k.at_2d::<f64>(1, 2)?,
            k1: dist(0)?,
            k2: dist(1)?,
            p1: dist(2)?,
            p2: dist(3)?,
            k3: dist(4)?,
        },
        rms_px: rms,
    })
}

fn mat3(m: &Mat) -> Result<[[f64; 3]; 3], CalibrationError> {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = *m.at_2d::<f64>(i as i32, j as i32)?;
        }
    }
    Ok(out)
}
