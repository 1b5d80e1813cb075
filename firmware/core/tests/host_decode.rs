//! Firmware with the host (issue 3, item 4): the core's sampling and framing logic produces the byte stream for
//! simulated physical motion, and the host's decoder (`fires_protocol::StreamDecoder`, the one `fires decode`
//! uses) reads it back: every packet decodes, counters are continuous, and the board's scale factors recover the
//! simulated values within one LSB.

use embassy_time::{Duration, Instant};
use fires_pen_core::board;
use fires_pen_core::sampler::{FrameSink, Framer, ImuSample, Outcome};
use fires_pen_core::status::{StatusInputs, StatusReporter};
use fires_protocol::{Buttons, Frame, StatusReason, StreamDecoder, FRAME_LEN};

/// The link: bytes in order, optionally refusing frames (backpressure).
struct Wire {
    bytes: Vec<u8>,
    refuse: bool,
}

impl FrameSink for Wire {
    fn try_send(&mut self, f: &[u8; FRAME_LEN]) -> bool {
        if self.refuse {
            return false;
        }
        self.bytes.extend_from_slice(f);
        true
    }
}

/// Simulated physical state at time `t` (s): acceleration m/s^2, angular rate rad/s, field T.
fn physics(t: f64) -> [[f64; 3]; 3] {
    let w = 2.0 * std::f64::consts::PI * 0.7;
    [
        [
            3.0 * (w * t).sin(),
            -2.0 * (w * t).cos(),
            9.80665 + 0.5 * (3.0 * w * t).sin(),
        ],
        [
            1.5 * (w * t).cos(),
            -0.8 * (2.0 * w * t).sin(),
            4.0 * (0.5 * w * t).sin(),
        ],
        [22e-6 * (w * t).cos(), 5e-6 * (w * t).sin(), -40e-6],
    ]
}

/// What the sensors would report: the value in counts, rounded to the nearest LSB.
fn to_counts(v: [f64; 3], scale: f64) -> [i16; 3] {
    v.map(|x| (x / scale).round().clamp(i16::MIN as f64, i16::MAX as f64) as i16)
}

fn simulate(ticks: usize, stall: std::ops::Range<usize>) -> (Vec<u8>, Framer, Vec<[[f64; 3]; 3]>) {
    let s = board::scale_factors();
    let mut wire = Wire {
        bytes: Vec::new(),
        refuse: false,
    };
    let mut framer = Framer::new();
    let t0 = Instant::from_millis(0);
    let mut status = StatusReporter::new(t0);
    let mut inputs = StatusInputs::default();
    status.send(StatusReason::Boot, &inputs, &framer, t0, &mut wire);
    let mut truth = Vec::new();
    for i in 0..ticks {
        let now = t0 + Duration::from_millis(10 * i as u64);
        let p = physics(now.as_micros() as f64 * 1e-6);
        let sample = ImuSample {
            accel: to_counts(p[0], s.accel_mps2_per_count),
            gyro: to_counts(p[1], s.gyro_radps_per_count),
            mag: to_counts(p[2], s.mag_tesla_per_count),
        };
        wire.refuse = stall.contains(&i);
        let out = framer.sensor(&sample, now.as_micros() as u32, &mut wire);
        if matches!(out, Outcome::Sent(_)) {
            truth.push(p);
        }
        wire.refuse = false;
        if status.periodic_due(now) {
            status.send(StatusReason::Periodic, &inputs, &framer, now, &mut wire);
        }
        if i == 333 {
            inputs.buttons = Buttons(0b0010);
            status.send(StatusReason::ButtonChange, &inputs, &framer, now, &mut wire);
        }
    }
    (wire.bytes, framer, truth)
}

#[test]
fn host_decoder_recovers_every_packet_and_value() {
    let ticks = 1000;
    let (bytes, framer, truth) = simulate(ticks, 0..0);
    let mut dec = StreamDecoder::new();
    let mut frames = Vec::new();
    dec.feed(&bytes, |d| frames.push(d));
    frames.extend(dec.finish());
    let stats = dec.stats();
    assert_eq!(stats.sensor_frames as usize, ticks);
    assert_eq!(
        stats.status_frames,
        1 + 9 + 1,
        "boot, periodic at 1..9 s, button change"
    );
    assert_eq!(stats.lost, 0);
    assert_eq!(stats.checksum_errors, 0);
    assert_eq!(
        stats.bytes_skipped, 0,
        "every byte belongs to a decoded frame"
    );
    assert_eq!(framer.dropped(), 0);

    let s = board::scale_factors();
    let scales = [
        s.accel_mps2_per_count,
        s.gyro_radps_per_count,
        s.mag_tesla_per_count,
    ];
    let mut expected_counter = 0u8;
    let mut k = 0;
    let mut status_seq = 0u8;
    for d in &frames {
        match d.frame {
            Frame::Sensor(p) => {
                assert_eq!(p.counter, expected_counter, "continuous counters");
                expected_counter = expected_counter.wrapping_add(1);
                let got = [p.accel, p.gyro, p.mag];
                for sensor in 0..3 {
                    for axis in 0..3 {
                        let phys = f64::from(got[sensor][axis]) * scales[sensor];
                        let err = (phys - truth[k][sensor][axis]).abs();
                        assert!(
                            err <= scales[sensor],
                            "sensor {sensor} axis {axis}: error {err} > 1 LSB"
                        );
                    }
                }
                k += 1;
            }
            Frame::Status(st) => {
                assert_eq!(st.sequence, status_seq);
                status_seq += 1;
                assert_eq!(
                    st.sensor_counter,
                    expected_counter.wrapping_sub(1),
                    "latest sent"
                );
                assert_eq!(st.protocol_version, fires_protocol::PROTOCOL_VERSION);
            }
        }
    }
    assert_eq!(k, ticks);
}

#[test]
fn backpressure_drops_show_up_as_loss_on_the_host() {
    let (bytes, framer, truth) = simulate(600, 100..130);
    assert_eq!(framer.dropped(), 30);
    let mut dec = StreamDecoder::new();
    let mut n = 0;
    dec.feed(&bytes, |_| n += 1);
    n += usize::from(dec.finish().is_some());
    let stats = dec.stats();
    assert_eq!(stats.sensor_frames as usize, truth.len());
    assert_eq!(
        stats.lost, 30,
        "the host counts exactly the dropped packets"
    );
    assert_eq!(stats.sensor_frames + stats.status_frames, n as u64);
    // the status packets report the drop count
    let mut last_status_dropped = 0;
    dec = StreamDecoder::new();
    dec.feed(&bytes, |d| {
        if let Frame::Status(s) = d.frame {
            last_status_dropped = s.dropped_packets;
        }
    });
    assert_eq!(last_status_dropped, 30);
}
