//! Which blob of a kept frame is which LED, for the time alignment (`pipeline/align.rs`): the
//! frame's own labels once a vision sample labelled it, else the images a recent vision pose
//! predicts, else the pen's pattern along the inertial direction (`pipeline/pattern.rs`).

use super::{KeptFrame, TimeAlignment};
use crate::stereo::{CameraId, StereoRig};
use crate::track::pen::LED_COUNT;
use crate::track::pipeline::pattern::label_by_pattern;

impl TimeAlignment {
    /// Blob index of every LED in a frame: its labels when a vision sample labelled it, otherwise
    /// the blob nearest each predicted LED image, accepted only when it is unambiguous (within a
    /// third of the smallest predicted LED spacing, and alone there); with no recent vision pose,
    /// the LEDs its pattern gives from the frame's [`PenGuess`] (`pipeline/pattern.rs`).
    pub(in crate::track::pipeline) fn frame_identities(
        &self,
        rig: &StereoRig,
        camera: CameraId,
        frame: &KeptFrame,
    ) -> [Option<usize>; LED_COUNT] {
        if frame.labels.iter().any(Option::is_some) {
            return frame.labels;
        }
        let predicted = self
            .predicted_images(rig, camera, frame.t_ns)
            .map(|px| nearest_identities(&px, &frame.blobs, self.options.max_blob_motion_px));
        if predicted.is_some_and(|ids| ids.iter().flatten().count() >= 3) {
            return predicted.unwrap_or_default();
        }
        // No prediction, or one that a turn of the pen has left behind: the pattern, unless it
        // contradicts what the prediction did find.
        let pen = &self.options.pen;
        let pattern = frame
            .guess
            .and_then(|g| g.images(rig, camera, &pen.led_offsets, pen.tip_offset))
            .and_then(|px| label_by_pattern(&px, &frame.blobs, &self.options.pattern));
        match (predicted, pattern) {
            (Some(p), Some(q)) if agree(&p, &q) => q,
            (None, Some(q)) => q,
            (p, _) => p.unwrap_or_default(),
        }
    }

    /// The images of the four LEDs in `camera` at `t` predicted by [`Self::predicted_leds`], or
    /// None without a prediction or when an LED does not project.
    pub(in crate::track::pipeline) fn predicted_images(
        &self,
        rig: &StereoRig,
        camera: CameraId,
        t: u64,
    ) -> Option<Vec<[f64; 2]>> {
        self.predicted_leds(t)?
            .iter()
            .map(|p| rig.project(camera, p))
            .collect::<Result<Vec<_>, _>>()
            .ok()
    }
}

/// The blob nearest each predicted LED image, accepted only when it is unambiguous (within a
/// third of the smallest predicted LED spacing, at most `max_spacing_px`, and alone there).
fn nearest_identities(
    px: &[[f64; 2]],
    blobs: &[[f64; 2]],
    max_spacing_px: f64,
) -> [Option<usize>; LED_COUNT] {
    let mut spacing = max_spacing_px;
    for (a, pa) in px.iter().enumerate() {
        for pb in &px[a + 1..] {
            spacing = spacing.min((pa[0] - pb[0]).hypot(pa[1] - pb[1]));
        }
    }
    let gate = spacing / 3.0;
    let mut ids = [None; LED_COUNT];
    for (id, p) in ids.iter_mut().zip(px) {
        let mut near = blobs
            .iter()
            .enumerate()
            .filter(|(_, b)| (b[0] - p[0]).hypot(b[1] - p[1]) <= gate);
        if let (Some((i, _)), None) = (near.next(), near.next()) {
            *id = Some(i);
        }
    }
    ids
}

/// True when two labellings give no LED two blobs and no blob two LEDs.
fn agree(a: &[Option<usize>; LED_COUNT], b: &[Option<usize>; LED_COUNT]) -> bool {
    (0..LED_COUNT).all(|k| {
        (0..LED_COUNT).all(|j| match (a[k], b[j]) {
            (Some(x), Some(y)) => (k == j) == (x == y),
            _ => true,
        })
    })
}
