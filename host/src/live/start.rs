//! Start-up re-tracking for a live session: the events of the session's start are kept in
//! memory until the online world estimate is accepted and every stroke begun before it has
//! ended; then a fresh tracker configured with that world tracks them once more, and its
//! strokes replace the live versions of the same ids when it tracked at least as many of their
//! points (the replay does the same over a recording, `replay/retrack.rs`). The live display
//! and samples stay the first pass's: they were shown as the pen moved.

use super::Event;
use crate::link::ButtonChange;
use crate::replay::retrack::{replace_strokes, retrack_until, second_is_better};
use crate::session::{Session, StrokeConfig};
use crate::stereo::StereoRig;
use crate::track::fusion::WorldReference;
use crate::track::pipeline::{Tracker, TrackerConfig};
use fires_record::Stroke;

/// The longest start kept waiting for the world estimate, nanoseconds: its blobs and IMU
/// samples take a few megabytes.
const MAX_START_NS: u64 = 120_000_000_000;

enum State {
    /// Keeping every event until the world estimate is accepted.
    Waiting,
    /// Keeping events until the end of the last stroke begun before `accepted_ns`.
    Until {
        accepted_ns: u64,
        world: WorldReference,
    },
    /// Re-tracked (the acceptance time and the second pass's strokes), or nothing to re-track.
    Done(Option<(u64, Vec<Stroke>)>),
}

/// The session's start, kept for re-tracking.
pub(super) struct StartBuffer {
    rig: StereoRig,
    tracker: TrackerConfig,
    strokes: StrokeConfig,
    events: Vec<Event>,
    /// The button changes among `events`.
    buttons: Vec<ButtonChange>,
    state: State,
}

impl StartBuffer {
    /// A buffer for a session tracked with `tracker` on `rig`; nothing is kept when the world
    /// reference is configured (there is no start-up to re-track).
    pub(super) fn new(rig: StereoRig, tracker: TrackerConfig, strokes: StrokeConfig) -> Self {
        let state = if tracker.world.is_some() {
            State::Done(None)
        } else {
            State::Waiting
        };
        Self {
            rig,
            tracker,
            strokes,
            events: Vec::new(),
            buttons: Vec::new(),
            state,
        }
    }

    /// Keeps `e` (before the live tracker sees it) while the start is being kept.
    pub(super) fn keep(&mut self, e: &Event) {
        if !matches!(self.state, State::Done(_)) {
            if let Event::Button(b) = e {
                self.buttons.push(*b);
            }
            self.events.push(e.clone());
        }
    }

    /// Moves on after the live tracker saw the events up to `t_ns`: starts waiting for the
    /// strokes begun before the acceptance once the world is accepted, re-tracks once they have
    /// ended, and gives up on a start longer than [`MAX_START_NS`].
    pub(super) fn update(&mut self, live: &Tracker, t_ns: u64) {
        let mask = self.strokes.draw_button_mask;
        match self.state {
            State::Waiting => {
                let first = self.events.first().map_or(t_ns, Event::t_ns);
                if let Some((accepted_ns, fit)) = live.world_fit().copied() {
                    self.state = match retrack_until(&self.buttons, mask, accepted_ns) {
                        Some(_) => State::Until {
                            accepted_ns,
                            world: fit.reference,
                        },
                        None => State::Done(None),
                    };
                } else if t_ns.saturating_sub(first) > MAX_START_NS {
                    self.state = State::Done(None);
                }
            }
            State::Until { accepted_ns, .. } => {
                // The pen-up of a stroke still drawn arrives later: the end is known only then.
                if retrack_until(&self.buttons, mask, accepted_ns).is_some_and(|u| t_ns > u) {
                    self.retrack();
                }
            }
            State::Done(_) => {}
        }
        if matches!(self.state, State::Done(_)) {
            self.events = Vec::new();
            self.buttons = Vec::new();
        }
    }

    /// The live strokes with the re-tracked start in place (tracked now if the session ended
    /// before the last start-up stroke did).
    pub(super) fn finish(mut self, live: Vec<Stroke>) -> Vec<Stroke> {
        if matches!(self.state, State::Until { .. }) {
            self.retrack();
        }
        match self.state {
            State::Done(Some((accepted_ns, second)))
                if second_is_better(&live, &second, accepted_ns) =>
            {
                replace_strokes(live, second, accepted_ns)
            }
            _ => live,
        }
    }

    /// Tracks the kept events once more with the accepted world.
    fn retrack(&mut self) {
        let State::Until {
            accepted_ns, world, ..
        } = self.state
        else {
            return;
        };
        let cfg = TrackerConfig {
            world: Some(world),
            ..self.tracker.clone()
        };
        let Ok(tracker) = Tracker::new(self.rig.clone(), cfg) else {
            self.state = State::Done(None);
            return;
        };
        let mut session = Session::new(tracker, self.strokes);
        let mut last = 0;
        for e in std::mem::take(&mut self.events) {
            last = e.t_ns();
            e.feed(&mut session);
        }
        session.finish(last);
        self.state = State::Done(Some((accepted_ns, session.into_strokes())));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::CameraId;
    use crate::track::pen::PenGeometry;
    use crate::track::pipeline::CameraFrame;
    use crate::track::synth::{imu_sample, project_leds, ImuNoise, PenMotion, SplitMix64};

    /// The events of a synthetic session of `seconds`: IMU at 200 Hz, both cameras at 60 Hz (the
    /// right 7 ms late) with 0.3 px of blob noise, LEDs 2 and 3 unseen over `hidden` and the draw
    /// button held over each of `strokes` (seconds).
    fn session_events(
        rig: &StereoRig,
        seconds: f64,
        hidden: (f64, f64),
        strokes: &[(f64, f64)],
    ) -> Vec<Event> {
        let pen = PenGeometry::thesis();
        let motion = PenMotion::drawing();
        let world = WorldReference::default();
        let mut rng = SplitMix64::new(3);
        let end = (seconds * 1e9) as u64;
        let mut events = Vec::new();
        for k in 1..end / 5_000_000 {
            let t = k * 5_000_000;
            events.push(Event::Imu(imu_sample(
                &motion,
                t,
                &world,
                &ImuNoise::default(),
                &mut rng,
            )));
        }
        for k in 1..end / 16_666_667 {
            for (c, camera) in [CameraId::Left, CameraId::Right].into_iter().enumerate() {
                let t = k * 16_666_667 + c as u64 * 7_000_000;
                let proj = project_leds(rig, &pen, &motion.pose(t as f64 * 1e-9), 0.3, &mut rng);
                // LEDs 2 and 3 hidden (by the hand) over `hidden`: two-LED frames.
                let hide = hidden.0 <= t as f64 * 1e-9 && t as f64 * 1e-9 < hidden.1;
                let blobs = (0..4)
                    .filter(|k| !(hide && (*k == 1 || *k == 2)))
                    .filter_map(|k| proj[c][k])
                    .collect();
                events.push(Event::Frame(CameraFrame::new(camera, t, blobs)));
            }
        }
        for &(a, b) in strokes {
            for (t, buttons) in [(a, 1), (b, 0)] {
                let t_ns = (t * 1e9) as u64;
                events.push(Event::Button(ButtonChange { t_ns, buttons }));
            }
        }
        events.sort_by_key(Event::t_ns);
        events
    }

    /// A stroke drawn from the first second, before the world estimate is accepted, is tracked
    /// once more with the accepted world when it has ended; its two-LED frames (LEDs 2 and 3
    /// hidden), which need the world's direction prior, are tracked then, so that version (same
    /// id, more points) takes the live one's place; the stroke drawn after the acceptance is the
    /// live one.
    #[test]
    fn the_start_is_retracked_once_the_world_is_accepted() {
        let rig = StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
        let strokes = StrokeConfig::default();
        let tracker = TrackerConfig::default();
        let mut live = Session::new(Tracker::new(rig.clone(), tracker.clone()).unwrap(), strokes);
        let mut start = StartBuffer::new(rig, tracker, strokes);
        let events = session_events(
            live.tracker().rig(),
            9.0,
            (1.0, 1.4),
            &[(0.3, 4.5), (7.0, 8.0)],
        );
        for e in events {
            let t = e.t_ns();
            start.keep(&e);
            e.feed(&mut live);
            start.update(live.tracker(), t);
        }
        let (accepted, _) = *live.tracker().world_fit().expect("world accepted");
        assert!(
            (300_000_000..4_500_000_000).contains(&accepted),
            "{accepted}"
        );
        let State::Done(Some((at, ref second))) = start.state else {
            panic!("not re-tracked");
        };
        assert_eq!(at, accepted);
        assert!(start.events.is_empty(), "the kept start is let go");
        let retracked = second.iter().find(|s| s.id == 0).expect("stroke 0").clone();
        assert!(second.iter().all(|s| s.t_start_ns < 4_700_000_000));
        live.finish(9_000_000_000);
        let first = live.into_strokes();
        let later = first.iter().find(|s| s.id == 1).expect("stroke 1").clone();
        let live_first = first.iter().find(|s| s.id == 0).expect("stroke 0");
        assert!(
            retracked.raw_points > live_first.raw_points,
            "raw points: live {} re-tracked {}",
            live_first.raw_points,
            retracked.raw_points
        );
        let out = start.finish(first);
        assert_eq!(out.iter().map(|s| s.id).collect::<Vec<_>>(), [0, 1]);
        assert!(
            out[0] == retracked,
            "the re-tracked stroke 0 replaces the live one"
        );
        assert!(out[1] == later, "stroke 1 is the live one");
    }
}
