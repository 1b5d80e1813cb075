//! From the link's byte chunks to timed IMU samples and button changes.
//!
//! Sensor packets carry no timestamp, only an 8-bit counter; the pen samples at a fixed rate. Each packet's
//! sample time is therefore `t_k = a + k·T` with `k` the unwrapped counter and `T` the pen's period. The
//! counter is unwrapped with the arrival times (the `k` that is congruent to the counter modulo 256 and closest
//! to the time-based guess), which survives outages longer than 256 packets. `a + k·T` is the lower envelope of
//! the arrivals over the session, a line: the radio only ever adds latency, so the line lies under every
//! arrival, and its slope is the pen clock's own period, which a crystal holds within about 50 ppm of nominal
//! (3 ms over a minute that a nominal period would leave in the timing; see `lower_envelope`). The live
//! timer ([`crate::link::imu_timing::LiveImuTimer`]) keeps the nominal period. A packet's arrival time is its
//! chunk's host time minus the serial time of the bytes after it.
//! Button changes come from status packets, timed at the sensor sample they name (`sensor_counter`).

use fires_protocol::{Frame, StreamDecoder, FRAME_LEN};
use fires_record::LinkChunk;

pub use crate::link::imu_timing::ButtonChange;
use crate::link::imu_timing::{change_age_samples, prev_counter_gap, unwrap_counter};
use crate::track::fusion::{ImuSample, ImuScale};

/// Everything the link carried, timed on the host clock.
#[derive(Debug, Clone, Default)]
pub struct ImuStream {
    /// IMU samples in SI units, in time order.
    pub samples: Vec<ImuSample>,
    /// Button states whenever they changed (the first status packet sets the initial state).
    pub buttons: Vec<ButtonChange>,
    /// The decoder's counters over the whole link.
    pub stats: fires_protocol::DecoderStats,
    /// Bytes on the link.
    pub bytes: u64,
}

/// A decoded frame with its arrival time.
struct Arrival {
    frame: Frame,
    arrival_ns: u64,
}

/// Decodes every chunk and times each frame by the serial position of its last byte within the chunk that
/// delivered that byte (the decoder may release a frame a few bytes later, in the next chunk).
fn decode_arrivals(
    chunks: &[LinkChunk],
    baud: u32,
) -> (Vec<Arrival>, fires_protocol::DecoderStats, u64) {
    let ns_per_byte = 10.0e9 / f64::from(baud.max(1));
    let mut ends = Vec::with_capacity(chunks.len());
    let mut total = 0u64;
    for c in chunks {
        total += c.bytes.len() as u64;
        ends.push(total);
    }
    let arrival = |end_offset: u64| -> u64 {
        let i = ends
            .partition_point(|&e| e < end_offset)
            .min(chunks.len().saturating_sub(1));
        let after = ends.get(i).map_or(0, |&e| e.saturating_sub(end_offset));
        let t = chunks.get(i).map_or(0, |c| c.host_time_ns);
        t.saturating_sub((after as f64 * ns_per_byte) as u64)
    };
    let mut decoder = StreamDecoder::new();
    let mut out = Vec::new();
    for chunk in chunks {
        decoder.feed(&chunk.bytes, |d| {
            out.push(Arrival {
                frame: d.frame,
                arrival_ns: arrival(d.end_offset),
            })
        });
    }
    if let Some(d) = decoder.finish() {
        out.push(Arrival {
            frame: d.frame,
            arrival_ns: arrival(d.end_offset),
        });
    }
    (out, decoder.stats(), total)
}

/// Decodes the link into timed IMU samples and button changes.
pub fn imu_stream(
    chunks: &[LinkChunk],
    baud: u32,
    sample_rate_hz: u32,
    scale: &ImuScale,
) -> ImuStream {
    let period_ns = 1e9 / f64::from(sample_rate_hz.max(1));
    let (arrivals, stats, bytes) = decode_arrivals(chunks, baud);
    let packet_ns = (FRAME_LEN as f64 * 10.0e9 / f64::from(baud.max(1))) as u64;
    let mut indexed = Vec::new();
    let mut prev: Option<(i64, u64)> = None;
    let mut statuses = Vec::new();
    for a in &arrivals {
        match a.frame {
            Frame::Sensor(p) => {
                let k = unwrap_counter(prev, p.counter, a.arrival_ns, period_ns);
                prev = Some((k, a.arrival_ns));
                indexed.push((k, a.arrival_ns, p));
            }
            Frame::Status(s) => statuses.push((prev, s)),
        }
    }
    // Lower envelope of arrival - k T, a line whose slope is the pen clock's rate error; the
    // packet's own serial time is part of the minimum latency.
    let residuals: Vec<(f64, f64)> = indexed
        .iter()
        .map(|(k, t, _)| (*k as f64, *t as f64 - *k as f64 * period_ns))
        .collect();
    let (anchor, skew) = lower_envelope(&residuals, MAX_SKEW * period_ns);
    let anchor = anchor - packet_ns as f64;
    let time_of = |k: i64| (anchor + k as f64 * (period_ns + skew)).max(0.0) as u64;
    let samples = indexed
        .iter()
        .map(|(k, _, p)| scale.to_si(time_of(*k), p.accel, p.gyro, p.mag))
        .collect();
    let mut buttons: Vec<ButtonChange> = Vec::new();
    for (prev, s) in statuses {
        // The status follows the sensor packet it names; place the change at that sample.
        let k = match prev {
            Some((k, _)) => {
                k - i64::from(prev_counter_gap(prev, s.sensor_counter))
                    - change_age_samples(s.reason, period_ns)
            }
            None => -1,
        };
        let t_ns = if anchor.is_finite() { time_of(k) } else { 0 };
        if buttons.last().is_none_or(|b| b.buttons != s.buttons.0) {
            buttons.push(ButtonChange {
                t_ns,
                buttons: s.buttons.0,
            });
        }
    }
    ImuStream {
        samples,
        buttons,
        stats,
        bytes,
    }
}

/// The largest rate error of the pen's clock taken from the arrivals, relative: ten times a
/// crystal's ±50 ppm tolerance. A larger fitted skew is the link's doing (latency that changed
/// for good, an outage), and the nominal period is kept.
const MAX_SKEW: f64 = 5e-4;

/// The line `a + s k` below every point `(k, y)` of `points` (k increasing) that lies closest to
/// them on average, as `(a, s)`, with `|s| <= max_slope` (else the plain minimum and slope 0).
///
/// The latency a radio adds is never negative, so the sample times are a line under the arrivals,
/// and the pen's clock rate error (the simulator's seeded ±50 ppm: up to 3 ms over a minute, which
/// a nominal period leaves in the IMU's timing of vision frames) is its slope. The line that
/// minimises the mean gap to the points subject to lying below all of them is the edge of their
/// lower convex hull above the mean `k` (Moon, Skelly and Towsley, "Estimation and removal of
/// clock skew from network delay measurements", INFOCOM 1999, the linear-programming bound).
fn lower_envelope(points: &[(f64, f64)], max_slope: f64) -> (f64, f64) {
    let minimum = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if points.len() < 2 {
        return (minimum, 0.0);
    }
    // Lower hull by the monotone chain.
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for &p in points {
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            // Drop b when it lies on or above the segment a-p.
            if (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0) <= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(p);
    }
    let mean = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
    let edge = hull
        .windows(2)
        .find(|w| w[0].0 <= mean && mean <= w[1].0 && w[1].0 > w[0].0);
    match edge {
        Some(w) => {
            let slope = (w[1].1 - w[0].1) / (w[1].0 - w[0].0);
            if slope.is_finite() && slope.abs() <= max_slope {
                (w[0].1 - slope * w[0].0, slope)
            } else {
                (minimum, 0.0)
            }
        }
        None => (minimum, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fires_protocol::{Buttons, SensorPacket, StatusPacket};

    /// The encoded sensor packet of sample `k` (its counter is `k` modulo 256).
    fn sensor(k: u64) -> [u8; 22] {
        SensorPacket {
            counter: k as u8,
            ..Default::default()
        }
        .encode()
    }

    fn chunk(t_ns: u64, frames: &[[u8; 22]]) -> LinkChunk {
        LinkChunk {
            host_time_ns: t_ns,
            bytes: frames.iter().flatten().copied().collect(),
        }
    }

    #[test]
    fn samples_are_timed_on_a_regular_grid_despite_latency_jitter() {
        let period = 10_000_000u64;
        let jitter = [3_000_000u64, 0, 7_000_000, 1_000_000, 4_000_000];
        let chunks: Vec<LinkChunk> = (0..600u64)
            .map(|k| {
                chunk(
                    1_000_000_000 + k * period + 2_000_000 + jitter[(k % 5) as usize],
                    &[sensor(k)],
                )
            })
            .collect();
        let s = imu_stream(&chunks, 230_400, 100, &ImuScale::default());
        assert_eq!(s.samples.len(), 600);
        for w in s.samples.windows(2) {
            assert_eq!(w[1].t_ns - w[0].t_ns, period);
        }
        // Anchored on the fastest packet (latency 2 ms, less its own serial time).
        let first = s.samples[0].t_ns as i64;
        assert!((first - 1_002_000_000).abs() < 1_000_000, "{first}");
    }

    /// A pen clock 40 ppm slow (2.4 ms over a minute) under a latency of 2-9 ms: the samples are
    /// timed on its own rate, each within 0.1 ms of its true time plus the fastest packet's
    /// latency, at the start of the session as at its end.
    #[test]
    fn a_drifting_pen_clock_is_timed_at_its_own_rate() {
        let true_period = 10_000_400.0;
        let latency = |k: u64| 2_000_000 + (k * 7919 % 13) * 540_000;
        let chunks: Vec<LinkChunk> = (0..6000u64)
            .map(|k| {
                let sampled = 1_000_000_000 + (k as f64 * true_period) as u64;
                chunk(sampled + latency(k), &[sensor(k)])
            })
            .collect();
        let s = imu_stream(&chunks, 230_400, 100, &ImuScale::default());
        assert_eq!(s.samples.len(), 6000);
        let packet_ns = (FRAME_LEN as f64 * 10.0e9 / 230_400.0) as i64;
        for k in [0usize, 3000, 5999] {
            let expected = 1_000_000_000 + (k as f64 * true_period) as i64 + 2_000_000 - packet_ns;
            let got = s.samples[k].t_ns as i64;
            assert!(
                (got - expected).abs() < 100_000,
                "sample {k}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn a_fitted_skew_beyond_a_crystal_s_is_the_link_s_and_is_not_taken() {
        // Latency that grows for good by 30 ms over 10 s (3000 ppm): the nominal period is kept.
        let points: Vec<(f64, f64)> = (0..1000).map(|k| (k as f64, 30_000.0 * k as f64)).collect();
        let (a, s) = lower_envelope(&points, MAX_SKEW * 10_000_000.0);
        assert_eq!((a, s), (0.0, 0.0));
        // Within the bound, the line under the points through the hull edge above their mean.
        let points: Vec<(f64, f64)> = (0..1000)
            .map(|k| {
                (
                    k as f64,
                    400.0 * k as f64 + if k % 7 == 0 { 0.0 } else { 5e5 },
                )
            })
            .collect();
        let (a, s) = lower_envelope(&points, MAX_SKEW * 10_000_000.0);
        assert!((s - 400.0).abs() < 1e-9 && a.abs() < 1e-6, "{a} {s}");
    }

    #[test]
    fn counters_unwrap_across_an_outage_longer_than_256_packets() {
        let period = 10_000_000u64;
        let ks: Vec<u64> = (0..50).chain(400..450).collect();
        let chunks: Vec<LinkChunk> = ks
            .iter()
            .map(|&k| chunk(k * period + 1_000_000, &[sensor(k)]))
            .collect();
        let s = imu_stream(&chunks, 230_400, 100, &ImuScale::default());
        assert_eq!(s.samples.len(), 100);
        let gap = s.samples[50].t_ns - s.samples[49].t_ns;
        assert_eq!(gap, 351 * period);
    }

    #[test]
    fn button_changes_are_placed_at_the_named_sample() {
        let period = 10_000_000u64;
        let mut frames = Vec::new();
        for k in 0..20u8 {
            frames.push(sensor(u64::from(k)));
            if k == 9 || k == 14 {
                let pressed = k == 9;
                frames.push(
                    StatusPacket {
                        sensor_counter: k,
                        sequence: u8::from(!pressed),
                        buttons: Buttons(u8::from(pressed)),
                        ..Default::default()
                    }
                    .encode(),
                );
            }
        }
        let chunks: Vec<LinkChunk> = frames
            .iter()
            .enumerate()
            .map(|(i, f)| chunk(i as u64 * period + 5_000_000, &[*f]))
            .collect();
        let s = imu_stream(&chunks, 230_400, 100, &ImuScale::default());
        assert_eq!(s.buttons.len(), 2);
        assert_eq!(s.buttons[0].buttons, 1);
        assert_eq!(s.buttons[1].buttons, 0);
        let t9 = s.samples[9].t_ns;
        let t14 = s.samples[14].t_ns;
        assert_eq!(s.buttons[0].t_ns, t9);
        assert_eq!(s.buttons[1].t_ns, t14);
    }
}
