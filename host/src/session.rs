//! One tracking session, fed in time order: IMU samples, button changes and camera frames through the
//! [`Tracker`], the button-delimited strokes (thesis §4.1.3), the real-time Gaussian display smoothing and the
//! end-of-stroke post-processing. Replay feeds it a recording's events sorted by time; live tracking feeds it
//! the same events through a short reorder buffer ([`crate::live`]), so both produce the same kind of output.

use std::time::Instant;

use crate::link::ButtonChange;
use crate::stroke::{
    postprocess, CausalSmoother, GaussianConfig, PostprocessConfig, StrokeEvent, StrokeSegmenter,
};
use crate::track::fusion::ImuSample;
use crate::track::pipeline::{CameraFrame, TrackSample, Tracker};

/// One finished stroke.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StrokeOut {
    /// Stroke number, from 0 in order of pen-down.
    pub id: u32,
    /// Pen-down host time, nanoseconds.
    pub t_start_ns: u64,
    /// Pen-up host time, nanoseconds.
    pub t_end_ns: u64,
    /// Tracked tip points of the stroke (raw, as the tracker gave them), metres.
    pub raw_points: usize,
    /// The post-processed polyline (sampling, constrained B-spline, resampling), metres.
    pub polyline_m: Vec<[f64; 3]>,
}

/// Stroke settings of a session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeConfig {
    /// Display smoothing of the tip (thesis: 300 taps, 3 passes).
    pub smoothing: GaussianConfig,
    /// Stroke post-processing.
    pub postprocess: PostprocessConfig,
    /// Mask of the button that draws (bit 0 = button 1).
    pub draw_button_mask: u8,
}

impl Default for StrokeConfig {
    fn default() -> Self {
        StrokeConfig {
            smoothing: GaussianConfig::default(),
            postprocess: PostprocessConfig::default(),
            draw_button_mask: 0b0001,
        }
    }
}

/// A tracker sample with the display-smoothed tip.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionSample {
    /// The tracker's sample.
    pub track: TrackSample,
    /// The tip after the real-time Gaussian smoothing (reset at every pen-down), metres.
    pub display_tip: Option<[f64; 3]>,
}

/// Tracker, strokes and smoothing of one session.
pub struct Session {
    tracker: Tracker,
    config: StrokeConfig,
    segmenter: StrokeSegmenter,
    smoother: CausalSmoother,
    drawing: bool,
    strokes: Vec<StrokeOut>,
    strokes_ns: u64,
}

impl Session {
    /// A session around a configured tracker.
    pub fn new(tracker: Tracker, config: StrokeConfig) -> Self {
        Session {
            tracker,
            smoother: CausalSmoother::new(&config.smoothing),
            config,
            segmenter: StrokeSegmenter::default(),
            drawing: false,
            strokes: Vec::new(),
            strokes_ns: 0,
        }
    }

    /// The tracker (for search windows and clock offsets).
    pub fn tracker(&self) -> &Tracker {
        &self.tracker
    }

    /// A button state from a status packet: pressing the draw button opens a stroke, releasing it
    /// closes and post-processes it. Returns the stroke that ended, if one did.
    pub fn button(&mut self, change: ButtonChange) -> Option<&StrokeOut> {
        let pressed = change.buttons & self.config.draw_button_mask != 0;
        if pressed == self.drawing {
            return None;
        }
        self.drawing = pressed;
        if pressed {
            self.smoother.reset();
        }
        let event = self.segmenter.button(change.t_ns, pressed);
        self.finish_stroke(event)
    }

    /// An IMU sample; returns a sample while the tip is dead-reckoned through an occlusion.
    pub fn imu(&mut self, sample: &ImuSample) -> Option<SessionSample> {
        let s = self.tracker.push_imu(sample)?;
        Some(self.sample(s))
    }

    /// A camera frame's blobs; returns a sample when it pairs with the other camera.
    pub fn frame(&mut self, frame: CameraFrame) -> Option<SessionSample> {
        let s = self.tracker.push_frame(frame)?;
        Some(self.sample(s))
    }

    /// Closes a stroke still open at `end_ns` (the session ended with the button held).
    pub fn finish(&mut self, end_ns: u64) -> Option<&StrokeOut> {
        if !self.drawing {
            return None;
        }
        self.drawing = false;
        let event = self.segmenter.button(end_ns, false);
        self.finish_stroke(event)
    }

    /// The finished strokes so far.
    pub fn strokes(&self) -> &[StrokeOut] {
        &self.strokes
    }

    /// Time spent post-processing strokes, nanoseconds.
    pub fn strokes_ns(&self) -> u64 {
        self.strokes_ns
    }

    /// The finished strokes.
    pub fn into_strokes(self) -> Vec<StrokeOut> {
        self.strokes
    }

    fn sample(&mut self, s: TrackSample) -> SessionSample {
        self.segmenter.tip(s.t_ns, s.tip);
        let display_tip = s.tip.map(|p| self.smoother.push(p));
        SessionSample {
            track: s,
            display_tip,
        }
    }

    fn finish_stroke(&mut self, event: Option<StrokeEvent>) -> Option<&StrokeOut> {
        let Some(StrokeEvent::Ended(stroke)) = event else {
            return None;
        };
        let t = Instant::now();
        let raw: Vec<[f64; 3]> = stroke.points.iter().map(|p| p.p).collect();
        let polyline_m = postprocess(&raw, &self.config.postprocess).unwrap_or(raw.clone());
        self.strokes.push(StrokeOut {
            id: self.strokes.len() as u32,
            t_start_ns: stroke.t_start_ns,
            t_end_ns: stroke.t_end_ns,
            raw_points: raw.len(),
            polyline_m,
        });
        self.strokes_ns += t.elapsed().as_nanos() as u64;
        self.strokes.last()
    }
}
