//! The sampling scheduler and the framing of sensor packets.
//!
//! - [`sample_loop`] wakes every 10 ms on an `embassy_time::Ticker`, takes the tick's timestamp first, then reads
//!   all three sensors back to back, so the nine axes of a packet belong to the same tick.
//! - [`Framer`] turns each tick into exactly one 22-byte sensor packet and offers it to a [`FrameSink`] **whole**:
//!   the sink either takes all 22 bytes or none. A packet the sink refuses (the UART or the radio is backed up) is
//!   dropped and counted, and still consumes its counter value, so the host sees the gap as loss
//!   (hardware-docs/protocol.md). A tick whose sensor read failed also consumes a counter value and is counted
//!   separately ([`Framer::read_errors`]).
//! - The framer remembers the counter and timestamp of the latest packet **sent**, which the status packet carries
//!   (the host's decoder uses that to check continuity between a sensor and a status packet).

use embassy_time::{Duration, Instant, Ticker};
use fires_protocol::{SensorPacket, FRAME_LEN};

use crate::drivers::bus::RegisterBus;
use crate::drivers::l3g4200d::L3g4200d;
use crate::drivers::lis3lv02dl::Lis3lv02dl;
use crate::drivers::mag3110::Mag3110;
use crate::drivers::{Axes, SensorError};

/// Nominal tick period (100 Hz).
pub const TICK: Duration = Duration::from_millis(1000 / fires_protocol::SAMPLE_RATE_HZ as u64);

/// The nine axes of one tick, raw counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuSample {
    /// Accelerometer x, y, z.
    pub accel: Axes,
    /// Gyroscope x, y, z.
    pub gyro: Axes,
    /// Magnetometer x, y, z.
    pub mag: Axes,
}

/// Where finished frames go: a bounded queue in front of the UART. Must take a frame whole or refuse it.
pub trait FrameSink {
    /// Queues all 22 bytes and returns true, or queues nothing and returns false.
    fn try_send(&mut self, frame: &[u8; FRAME_LEN]) -> bool;
}

/// What happened to one tick's packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// Queued with this counter.
    Sent(u8),
    /// Refused by the sink; this counter value is lost.
    Dropped(u8),
    /// The sensor read failed; this counter value is lost.
    ReadError(u8),
}

/// Counter and drop bookkeeping of the sensor packet stream.
#[derive(Clone, Debug)]
pub struct Framer {
    next_counter: u8,
    last_sent: u8,
    last_sent_time_us: Option<u32>,
    dropped: u32,
    read_errors: u32,
    sent: u32,
}

impl Default for Framer {
    fn default() -> Self {
        Self::new()
    }
}

impl Framer {
    /// A framer whose first packet gets counter 0. Before any packet is sent, the "latest sent" counter is 255,
    /// so a status packet sent first is continued by sensor packet 0.
    pub const fn new() -> Self {
        Framer {
            next_counter: 0,
            last_sent: u8::MAX,
            last_sent_time_us: None,
            dropped: 0,
            read_errors: 0,
            sent: 0,
        }
    }

    /// Frames one tick's sample taken at `time_us` (device microseconds) and offers it to `sink`.
    pub fn sensor(
        &mut self,
        sample: &ImuSample,
        time_us: u32,
        sink: &mut impl FrameSink,
    ) -> Outcome {
        let counter = self.take_counter();
        let packet = SensorPacket {
            counter,
            accel: sample.accel,
            gyro: sample.gyro,
            mag: sample.mag,
        };
        if sink.try_send(&packet.encode()) {
            self.last_sent = counter;
            self.last_sent_time_us = Some(time_us);
            self.sent = self.sent.wrapping_add(1);
            Outcome::Sent(counter)
        } else {
            self.dropped = self.dropped.wrapping_add(1);
            Outcome::Dropped(counter)
        }
    }

    /// A tick whose read failed: consumes its counter value, sends nothing.
    pub fn read_failed(&mut self) -> Outcome {
        self.read_errors = self.read_errors.wrapping_add(1);
        Outcome::ReadError(self.take_counter())
    }

    fn take_counter(&mut self) -> u8 {
        let c = self.next_counter;
        self.next_counter = c.wrapping_add(1);
        c
    }

    /// Counter of the latest packet sent (255 before the first).
    pub fn last_sent_counter(&self) -> u8 {
        self.last_sent
    }

    /// Device time of the latest packet sent.
    pub fn last_sent_time_us(&self) -> Option<u32> {
        self.last_sent_time_us
    }

    /// Packets refused by the sink since power-on.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Ticks lost to sensor read errors since power-on.
    pub fn read_errors(&self) -> u32 {
        self.read_errors
    }

    /// Packets sent since power-on.
    pub fn sent(&self) -> u32 {
        self.sent
    }
}

/// A source of all nine axes at once.
#[allow(async_fn_in_trait)] // single-threaded embedded executors: no Send bound needed
pub trait Imu {
    /// Read error.
    type Error;
    /// Reads accelerometer, gyroscope and magnetometer back to back.
    async fn read_all(&mut self) -> Result<ImuSample, Self::Error>;
}

/// The pen's three sensors, read in the order accelerometer, gyroscope, magnetometer.
#[derive(Debug)]
pub struct PenImu<A, G, M> {
    /// Accelerometer.
    pub accel: Lis3lv02dl<A>,
    /// Gyroscope.
    pub gyro: L3g4200d<G>,
    /// Magnetometer.
    pub mag: Mag3110<M>,
}

impl<E, A, G, M> Imu for PenImu<A, G, M>
where
    A: RegisterBus<Error = E>,
    G: RegisterBus<Error = E>,
    M: RegisterBus<Error = E>,
{
    type Error = SensorError<E>;
    async fn read_all(&mut self) -> Result<ImuSample, SensorError<E>> {
        Ok(ImuSample {
            accel: self.accel.read().await?,
            gyro: self.gyro.read().await?,
            mag: self.mag.read().await?,
        })
    }
}

/// Runs the sampling schedule: every `period`, timestamp the tick, read all axes, hand both to `on_tick`.
/// Stops when `on_tick` returns false. A tick that comes late (a read took longer than a period) is followed
/// immediately by the next one, as `Ticker` catches up; nothing is skipped silently.
pub async fn sample_loop<I: Imu>(
    imu: &mut I,
    period: Duration,
    mut on_tick: impl FnMut(Result<ImuSample, I::Error>, Instant) -> bool,
) {
    let mut ticker = Ticker::every(period);
    loop {
        ticker.next().await;
        let at = Instant::now();
        let r = imu.read_all().await;
        if !on_tick(r, at) {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// A sink with room for `room` frames.
    struct Queue {
        room: usize,
        frames: Vec<[u8; FRAME_LEN]>,
    }
    impl FrameSink for Queue {
        fn try_send(&mut self, f: &[u8; FRAME_LEN]) -> bool {
            if self.frames.len() < self.room {
                self.frames.push(*f);
                true
            } else {
                false
            }
        }
    }

    #[test]
    fn counters_and_whole_packet_drops() {
        let mut q = Queue {
            room: 3,
            frames: Vec::new(),
        };
        let mut f = Framer::new();
        assert_eq!(f.last_sent_counter(), 255);
        let s = ImuSample {
            accel: [1, 2, 3],
            gyro: [4, 5, 6],
            mag: [7, 8, 9],
        };
        let out: Vec<Outcome> = (0..5).map(|i| f.sensor(&s, i * 10_000, &mut q)).collect();
        assert_eq!(
            out,
            [
                Outcome::Sent(0),
                Outcome::Sent(1),
                Outcome::Sent(2),
                Outcome::Dropped(3),
                Outcome::Dropped(4)
            ]
        );
        assert_eq!(f.dropped(), 2);
        assert_eq!(f.last_sent_counter(), 2);
        assert_eq!(f.last_sent_time_us(), Some(20_000));
        // every queued frame is a complete 22-byte packet
        assert!(q.frames.iter().all(|fr| fr[0] == 0x20 && fr[1] == 0x0A));
        q.room = 10;
        assert_eq!(f.read_failed(), Outcome::ReadError(5));
        assert_eq!(f.sensor(&s, 60_000, &mut q), Outcome::Sent(6));
        assert_eq!(f.read_errors(), 1);
        assert_eq!(f.sent(), 4);
    }

    #[test]
    fn counter_wraps() {
        let mut q = Queue {
            room: 1000,
            frames: Vec::new(),
        };
        let mut f = Framer::new();
        for _ in 0..257 {
            f.sensor(&ImuSample::default(), 0, &mut q);
        }
        assert_eq!(q.frames[255][2], 255);
        assert_eq!(q.frames[256][2], 0);
    }
}
