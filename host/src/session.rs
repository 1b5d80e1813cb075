//! One tracking session, fed in time order: IMU samples, button changes and camera frames through the
//! [`Tracker`], the button-delimited strokes (thesis §4.1.3), the real-time display smoothing (the One Euro filter by
//! default, the thesis's causal Gaussian as an option) and the
//! end-of-stroke post-processing. Replay feeds it a recording's events sorted by time; live tracking feeds it
//! the same events through a short reorder buffer ([`crate::live`]), so both produce the same kind of output.

use std::time::Instant;

use crate::link::ButtonChange;
use crate::stroke::{
    stroke_record, CausalSmoother, GaussianConfig, OneEuroConfig, OneEuroFilter, StrokeEvent,
    StrokeRecordConfig, StrokeSegmenter,
};
use crate::track::fusion::ImuSample;
use crate::track::pipeline::{CameraFrame, TrackQuality, TrackSample, Tracker};
use fires_record::Stroke;

/// The filter behind the live display of the tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DisplayFilter {
    /// The One Euro filter (Casiez et al., CHI 2012), tuned for a pen: follows the pen with a few ms of lag.
    OneEuro(OneEuroConfig),
    /// The thesis's causal Gaussian (§4.1.3: 300 taps, 3 passes); steady but trails the pen by about 0.5 s.
    Thesis(GaussianConfig),
}

impl Default for DisplayFilter {
    fn default() -> Self {
        DisplayFilter::OneEuro(OneEuroConfig::default())
    }
}

impl DisplayFilter {
    /// The name used on the command line and in `report.json`: "one-euro" or "thesis".
    pub fn name(&self) -> &'static str {
        match self {
            DisplayFilter::OneEuro(_) => "one-euro",
            DisplayFilter::Thesis(_) => "thesis",
        }
    }
}

/// A display filter's running state.
#[derive(Debug, Clone)]
enum DisplayState {
    OneEuro(OneEuroFilter),
    Thesis(CausalSmoother),
}

impl DisplayState {
    fn new(filter: &DisplayFilter) -> Self {
        match filter {
            DisplayFilter::OneEuro(c) => DisplayState::OneEuro(OneEuroFilter::new(*c)),
            DisplayFilter::Thesis(c) => DisplayState::Thesis(CausalSmoother::new(c)),
        }
    }

    fn reset(&mut self) {
        match self {
            DisplayState::OneEuro(f) => f.reset(),
            DisplayState::Thesis(f) => f.reset(),
        }
    }

    fn push(&mut self, t_ns: u64, p: [f64; 3]) -> [f64; 3] {
        match self {
            DisplayState::OneEuro(f) => f.push(t_ns, p),
            DisplayState::Thesis(f) => f.push(p),
        }
    }
}

/// Stroke settings of a session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeConfig {
    /// Display smoothing of the tip (default: One Euro).
    pub display: DisplayFilter,
    /// Post-processing and the strokes-file record of a finished stroke.
    pub record: StrokeRecordConfig,
    /// Mask of the button that draws (bit 0 = button 1).
    pub draw_button_mask: u8,
}

impl Default for StrokeConfig {
    fn default() -> Self {
        StrokeConfig {
            display: DisplayFilter::default(),
            record: StrokeRecordConfig::default(),
            draw_button_mask: 0b0001,
        }
    }
}

/// A tracker sample with the display-smoothed tip.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionSample {
    /// The tracker's sample.
    pub track: TrackSample,
    /// The tip after the real-time display filter (reset at every pen-down), metres.
    pub display_tip: Option<[f64; 3]>,
}

/// Tracker, strokes and smoothing of one session.
pub struct Session {
    tracker: Tracker,
    config: StrokeConfig,
    segmenter: StrokeSegmenter,
    smoother: DisplayState,
    drawing: bool,
    /// Pen-down events so far: the next stroke's id.
    pen_downs: u32,
    /// Buttons held at the open stroke's pen-down.
    buttons: u8,
    strokes: Vec<Stroke>,
    strokes_ns: u64,
}

impl Session {
    /// A session around a configured tracker.
    pub fn new(tracker: Tracker, config: StrokeConfig) -> Self {
        Session {
            tracker,
            smoother: DisplayState::new(&config.display),
            config,
            segmenter: StrokeSegmenter::default(),
            drawing: false,
            pen_downs: 0,
            buttons: 0,
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
    pub fn button(&mut self, change: ButtonChange) -> Option<&Stroke> {
        let pressed = change.buttons & self.config.draw_button_mask != 0;
        if pressed == self.drawing {
            return None;
        }
        self.drawing = pressed;
        if pressed {
            self.smoother.reset();
            self.buttons = change.buttons;
        }
        let event = self.segmenter.button(change.t_ns, pressed);
        self.finish_stroke(event)
    }

    /// An IMU sample; returns a sample while the tip is dead-reckoned through an occlusion.
    pub fn imu(&mut self, sample: &ImuSample) -> Option<SessionSample> {
        let s = self.tracker.push_imu(sample);
        if let Some((t, a)) = self.tracker.tip_acceleration() {
            self.segmenter.accel(t, a);
        }
        Some(self.sample(s?))
    }

    /// A camera frame's blobs; returns a sample when it pairs with the other camera.
    pub fn frame(&mut self, frame: CameraFrame) -> Option<SessionSample> {
        let s = self.tracker.push_frame(frame)?;
        Some(self.sample(s))
    }

    /// Closes a stroke still open at `end_ns` (the session ended with the button held).
    pub fn finish(&mut self, end_ns: u64) -> Option<&Stroke> {
        if !self.drawing {
            return None;
        }
        self.drawing = false;
        let event = self.segmenter.button(end_ns, false);
        self.finish_stroke(event)
    }

    /// The finished strokes so far.
    pub fn strokes(&self) -> &[Stroke] {
        &self.strokes
    }

    /// Time spent post-processing strokes, nanoseconds.
    pub fn strokes_ns(&self) -> u64 {
        self.strokes_ns
    }

    /// The finished strokes.
    pub fn into_strokes(self) -> Vec<Stroke> {
        self.strokes
    }

    fn sample(&mut self, s: TrackSample) -> SessionSample {
        // Strokes keep what the cameras saw: a dead-reckoned tip drifts by centimetres within a
        // fraction of a second on a webcam rig, so it is shown live but never drawn into a stroke;
        // a gap between vision tips becomes a split into pieces (docs/strokes.md).
        if matches!(s.quality, TrackQuality::Vision { .. }) {
            // The vision tip along the stroke axis as the tracker reports it (the tip filter's when
            // enabled: on fires-v1 it gives 0.42-0.56 mm stroke RMS medians against 0.48-0.62 from
            // the raw tips; its uncertainty is at most the frame's own `stroke_tip_sigma_m`); the
            // end-of-stroke spline smooths it over the stroke.
            self.segmenter
                .tip_with_sigma(s.t_ns, s.stroke_tip, s.stroke_tip_sigma_m);
        }
        let display_tip = s.tip.map(|p| self.smoother.push(s.t_ns, p));
        SessionSample {
            track: s,
            display_tip,
        }
    }

    fn finish_stroke(&mut self, event: Option<StrokeEvent>) -> Option<&Stroke> {
        let ended = match event? {
            StrokeEvent::Started { .. } => return None,
            StrokeEvent::Discarded { .. } => None,
            StrokeEvent::Ended(stroke) => Some(stroke),
        };
        // Ids count pen-downs, kept or not, so re-tracking a session keeps every stroke's id.
        let id = self.pen_downs;
        self.pen_downs += 1;
        let stroke = ended?;
        let t = Instant::now();
        let record = stroke_record(id, self.buttons, &stroke, &self.config.record);
        self.strokes.push(record);
        self.strokes_ns += t.elapsed().as_nanos() as u64;
        self.strokes.last()
    }
}
