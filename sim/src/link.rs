//! The pen -> host link: the pen's packet scheduling (sensor packets at 100 Hz, status packets at 1 Hz and on
//! button changes), the UART at 230400 baud 8N1, and the Bluetooth radio (batched delivery with latency jitter,
//! dropped and corrupted bytes, whole packets lost, disconnections).
//!
//! Protocol rules honoured (the host decoder needs them to lock): the sensor counter advances by one per packet
//! produced, including packets the pen drops itself (backpressure); a status packet's `sensor_counter` is the
//! counter of the latest sensor packet the pen actually sent before it (0xFF before the first) and its
//! `device_time_us` that packet's sample time; the status `sequence` advances by one per status packet.

use crate::rng::SimRng;
use fires_protocol::{
    Buttons, Frame, Health, SensorPacket, StateFlags, StatusPacket, StatusReason,
    BUTTON_REPEAT_AFTER_US, FRAME_LEN, LINK_BAUD, PROTOCOL_VERSION,
};
use fires_record::{Interval, LinkChunk, PacketFate, PacketTruth};

/// Link fault and timing model.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkConfig {
    /// Probability that the pen drops a sensor packet itself (counter consumed, never sent).
    pub pen_drop_prob: f64,
    /// Probability that a whole packet is lost in the radio.
    pub packet_loss_prob: f64,
    /// Probability per byte that it is lost.
    pub byte_drop_prob: f64,
    /// Probability per byte that it arrives corrupted.
    pub byte_corrupt_prob: f64,
    /// Fixed radio latency, seconds.
    pub latency_s: f64,
    /// Mean of the exponential extra latency, seconds.
    pub latency_jitter_s: f64,
    /// Range of the radio's flush interval (bytes are delivered in batches), seconds.
    pub flush_interval_s: (f64, f64),
    /// Disconnections `(start, duration)`, seconds of session time.
    pub disconnects: Vec<(f64, f64)>,
    /// Delay from sampling to the first byte on the UART, seconds.
    pub processing_s: f64,
    /// Period of the periodic status packet, seconds of device time.
    pub status_period_s: f64,
}

impl LinkConfig {
    /// A clean link: latency and batching only.
    pub fn clean() -> Self {
        LinkConfig {
            pen_drop_prob: 0.0,
            packet_loss_prob: 0.0,
            byte_drop_prob: 0.0,
            byte_corrupt_prob: 0.0,
            latency_s: 0.006,
            latency_jitter_s: 0.003,
            flush_interval_s: (0.002, 0.012),
            disconnects: Vec::new(),
            processing_s: 0.0003,
            status_period_s: 1.0,
        }
    }

    /// Whether session time `t` lies in a disconnection.
    pub fn disconnected(&self, t: f64) -> bool {
        self.disconnects.iter().any(|&(a, d)| t >= a && t < a + d)
    }
}

/// A packet produced by the pen, ready to be sent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Produced {
    /// Session time at which its first byte may go on the UART, seconds.
    pub t_ready: f64,
    /// The packet.
    pub frame: Frame,
    /// Dropped by the pen (never sent).
    pub pen_dropped: bool,
}

/// The pen firmware's packet scheduler.
#[derive(Clone, Debug)]
pub struct PenFirmware {
    sequence: u8,
    last_sent: Option<(u8, u64)>,
    dropped: u32,
    buttons: Option<u8>,
    next_status_us: u64,
    status_period_us: u64,
    battery_mv: f64,
    /// Device time of the latest button change and the repeats of it sent (as the firmware's
    /// `StatusReporter`: [`BUTTON_REPEAT_AFTER_US`] later).
    repeat: Option<(u64, usize)>,
}

impl PenFirmware {
    /// A pen that has just booted.
    pub fn new(status_period_s: f64) -> Self {
        PenFirmware {
            sequence: 0,
            last_sent: None,
            dropped: 0,
            buttons: None,
            next_status_us: 0,
            status_period_us: (status_period_s * 1e6).round().max(1.0) as u64,
            battery_mv: 3950.0,
            repeat: None,
        }
    }

    fn status(&mut self, reason: StatusReason, buttons: u8, connected: bool) -> StatusPacket {
        let (counter, time) = self.last_sent.unwrap_or((0xFF, 0));
        let mut flags = StateFlags::STREAMING | StateFlags::IR_LEDS_ON;
        if connected {
            flags |= StateFlags::CONNECTED;
        }
        let p = StatusPacket {
            sequence: self.sequence,
            sensor_counter: counter,
            device_time_us: time as u32,
            buttons: Buttons(buttons),
            flags: StateFlags(flags),
            health: Health(Health::ALL_GOOD),
            reason,
            battery_mv: self.battery_mv.round() as u16,
            dropped_packets: self.dropped,
            firmware_version: (0, 1),
            protocol_version: PROTOCOL_VERSION,
        };
        self.sequence = self.sequence.wrapping_add(1);
        p
    }

    /// Handles one IMU sample: returns the packets produced, in sending order.
    #[allow(clippy::too_many_arguments)]
    pub fn on_sample(
        &mut self,
        t: f64,
        device_time_us: u64,
        packet: SensorPacket,
        buttons: u8,
        cfg: &LinkConfig,
        rng: &mut SimRng,
        out: &mut Vec<Produced>,
    ) {
        let connected = !cfg.disconnected(t);
        let ready = t + cfg.processing_s;
        if self.buttons.is_none() {
            let p = self.status(StatusReason::Boot, buttons, connected);
            out.push(Produced {
                t_ready: ready,
                frame: Frame::Status(p),
                pen_dropped: false,
            });
            self.next_status_us = device_time_us + self.status_period_us;
        }
        let pen_dropped = rng.chance(cfg.pen_drop_prob);
        if pen_dropped {
            self.dropped += 1;
        } else {
            self.last_sent = Some((packet.counter, device_time_us));
        }
        out.push(Produced {
            t_ready: ready,
            frame: Frame::Sensor(packet),
            pen_dropped,
        });
        let reason = if self.buttons.is_some_and(|b| b != buttons) {
            Some(StatusReason::ButtonChange)
        } else if device_time_us >= self.next_status_us {
            Some(StatusReason::Periodic)
        } else {
            None
        };
        self.buttons = Some(buttons);
        if let Some((at, sent)) = self.repeat {
            let due = BUTTON_REPEAT_AFTER_US.get(sent).map(|&d| at + u64::from(d));
            if due.is_some_and(|due| device_time_us >= due) {
                self.repeat = Some((at, sent + 1));
                let p = self.status(StatusReason::ButtonRepeat(sent as u8), buttons, connected);
                out.push(Produced {
                    t_ready: ready + 5e-5,
                    frame: Frame::Status(p),
                    pen_dropped: false,
                });
            }
        }
        if let Some(reason) = reason {
            if reason == StatusReason::Periodic || device_time_us >= self.next_status_us {
                self.next_status_us += self.status_period_us;
            }
            self.battery_mv -= 0.05;
            let p = self.status(reason, buttons, connected);
            if reason == StatusReason::ButtonChange {
                self.repeat = Some((device_time_us, 0));
            }
            out.push(Produced {
                t_ready: ready + 1e-4,
                frame: Frame::Status(p),
                pen_dropped: false,
            });
        }
    }
}

/// Everything the link produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinkOutput {
    /// Bytes as the host receives them.
    pub chunks: Vec<LinkChunk>,
    /// Every produced packet and its fate, in production order.
    pub truth: Vec<PacketTruth>,
    /// Disconnections in host time.
    pub disconnects: Vec<Interval>,
}

/// Host-clock nanoseconds of session time `t` seconds.
pub fn host_ns(origin_ns: u64, t: f64) -> u64 {
    origin_ns.saturating_add((t.max(0.0) * 1e9).round() as u64)
}

/// Sends the packets through the UART and the radio.
pub fn transmit(
    packets: &[Produced],
    cfg: &LinkConfig,
    host_origin_ns: u64,
    rng: &mut SimRng,
) -> LinkOutput {
    let byte_time = 10.0 / f64::from(LINK_BAUD);
    let mut uart_free = 0.0f64;
    let mut wire: Vec<(f64, u8)> = Vec::with_capacity(packets.len() * FRAME_LEN);
    let mut truth = Vec::with_capacity(packets.len());
    for p in packets {
        if p.pen_dropped {
            truth.push(PacketTruth {
                send_time_ns: host_ns(host_origin_ns, p.t_ready),
                frame: p.frame,
                fate: PacketFate::PenDropped,
            });
            continue;
        }
        let start = p.t_ready.max(uart_free);
        uart_free = start + FRAME_LEN as f64 * byte_time;
        let fate = if cfg.disconnected(start) {
            PacketFate::Disconnected
        } else if rng.chance(cfg.packet_loss_prob) {
            PacketFate::Lost
        } else {
            let mut damaged = false;
            for (j, &b) in p.frame.encode().iter().enumerate() {
                let t = start + (j + 1) as f64 * byte_time;
                if rng.chance(cfg.byte_drop_prob) {
                    damaged = true;
                } else if rng.chance(cfg.byte_corrupt_prob) {
                    damaged = true;
                    wire.push((t, b ^ (1 + rng.below(255) as u8)));
                } else {
                    wire.push((t, b));
                }
            }
            if damaged {
                PacketFate::Damaged
            } else {
                PacketFate::Delivered
            }
        };
        truth.push(PacketTruth {
            send_time_ns: host_ns(host_origin_ns, start),
            frame: p.frame,
            fate,
        });
    }
    // Radio: bytes are batched and delivered in order after a jittered latency.
    let mut chunks = Vec::new();
    let mut i = 0;
    let mut last_delivery = 0.0f64;
    let mut flush = wire.first().map_or(0.0, |w| w.0);
    while i < wire.len() {
        flush += rng
            .range(cfg.flush_interval_s.0, cfg.flush_interval_s.1)
            .max(1e-5);
        if wire[i].0 > flush {
            continue;
        }
        let mut bytes = Vec::new();
        while i < wire.len() && wire[i].0 <= flush {
            bytes.push(wire[i].1);
            i += 1;
        }
        let delivery =
            (flush + cfg.latency_s + rng.exponential(cfg.latency_jitter_s)).max(last_delivery);
        last_delivery = delivery;
        chunks.push(LinkChunk {
            host_time_ns: host_ns(host_origin_ns, delivery),
            bytes,
        });
    }
    let disconnects = cfg
        .disconnects
        .iter()
        .map(|&(a, d)| Interval {
            start_ns: host_ns(host_origin_ns, a),
            end_ns: host_ns(host_origin_ns, a + d),
        })
        .collect();
    LinkOutput {
        chunks,
        truth,
        disconnects,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packets(n: usize, cfg: &LinkConfig, buttons_at: impl Fn(usize) -> u8) -> Vec<Produced> {
        let mut fw = PenFirmware::new(cfg.status_period_s);
        let mut rng = SimRng::stream(1, 1);
        let mut out = Vec::new();
        for k in 0..n {
            let p = SensorPacket {
                counter: k as u8,
                ..SensorPacket::default()
            };
            fw.on_sample(
                k as f64 * 0.01,
                k as u64 * 10_000,
                p,
                buttons_at(k),
                cfg,
                &mut rng,
                &mut out,
            );
        }
        out
    }

    #[test]
    fn status_packets_follow_the_protocol_rules() {
        let cfg = LinkConfig {
            pen_drop_prob: 0.05,
            ..LinkConfig::clean()
        };
        let out = packets(450, &cfg, |k| u8::from((100..250).contains(&k)));
        let mut last_sent: Option<u8> = None;
        let mut seq = 0u8;
        let mut reasons = Vec::new();
        let mut last_change = None;
        for p in &out {
            match p.frame {
                Frame::Sensor(s) if !p.pen_dropped => last_sent = Some(s.counter),
                Frame::Sensor(_) => {}
                Frame::Status(s) => {
                    assert_eq!(s.sequence, seq);
                    seq = seq.wrapping_add(1);
                    assert_eq!(s.sensor_counter, last_sent.unwrap_or(0xFF));
                    if let StatusReason::ButtonRepeat(n) = s.reason {
                        // 30 and 100 ms after the change (about 3 and 10 samples), same buttons.
                        let (c, b) = last_change.expect("a change before its repeat");
                        let after = s.sensor_counter.wrapping_sub(c);
                        let range = [2..=4u8, 8..=11][usize::from(n)].clone();
                        assert!(range.contains(&after), "repeat {n} {after} samples after");
                        assert_eq!(s.buttons, b);
                    }
                    if s.reason == StatusReason::ButtonChange {
                        last_change = Some((s.sensor_counter, s.buttons));
                    }
                    reasons.push((s.reason, s.buttons.0));
                }
            }
        }
        // Boot, periodic at 1 s intervals (k = 100, 200, 300, 400) and two button changes (k = 100, 250).
        assert_eq!(reasons[0].0, StatusReason::Boot);
        let changes: Vec<_> = reasons
            .iter()
            .filter(|r| r.0 == StatusReason::ButtonChange)
            .collect();
        assert_eq!(changes.len(), 2);
        assert_eq!((changes[0].1, changes[1].1), (1, 0));
        // Each change is sent twice more, 30 ms and 100 ms later (3 and 10 samples at 100 Hz).
        let repeats = reasons
            .iter()
            .filter(|r| matches!(r.0, StatusReason::ButtonRepeat(_)))
            .count();
        assert_eq!(repeats, 4);
        assert_eq!(
            reasons.len(),
            1 + 4 + 2 - 1 + 4,
            "the button change at 1 s also serves as that second's report"
        );
    }

    #[test]
    fn the_uart_runs_at_230400_baud_and_delivery_is_in_order() {
        let cfg = LinkConfig::clean();
        let out = packets(300, &cfg, |_| 0);
        let link = transmit(&out, &cfg, 0, &mut SimRng::stream(2, 2));
        let bytes: usize = link.chunks.iter().map(|c| c.bytes.len()).sum();
        assert_eq!(bytes, out.len() * FRAME_LEN);
        let sent: Vec<u8> = out.iter().flat_map(|p| p.frame.encode()).collect();
        let got: Vec<u8> = link.chunks.iter().flat_map(|c| c.bytes.clone()).collect();
        assert_eq!(got, sent);
        assert!(link
            .chunks
            .windows(2)
            .all(|w| w[0].host_time_ns <= w[1].host_time_ns));
        // Sensor and status packets sent back to back occupy the UART for 22 * 10 / 230400 s each.
        let t: Vec<u64> = link.truth.iter().map(|p| p.send_time_ns).collect();
        let frame_ns = (22.0 * 10.0 / 230_400.0 * 1e9) as u64;
        assert!(t.windows(2).all(|w| w[1] >= w[0] + frame_ns - 1));
        // Latency: every byte arrives after it was sent, at least the fixed latency later.
        let first = link.chunks[0].host_time_ns;
        assert!(first >= t[0] + frame_ns + (cfg.latency_s * 1e9) as u64 - 1);
    }
}
