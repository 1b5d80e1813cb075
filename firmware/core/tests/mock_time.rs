//! Timing-dependent behaviour under embassy-time's mock driver: time only moves when the test advances it.
//!
//! The mock driver is one global clock per test binary, so every test here takes `CLOCK` first and resets the
//! driver; the tests run one after the other.

use std::collections::VecDeque;
use std::future::Future;
use std::pin::pin;
use std::sync::Mutex;
use std::task::{Context, Poll, Waker};

use embassy_time::{Duration, Instant, MockDriver, Timer};
use fires_pen_core::iwrap::{provision_module, Config, ModemPort, ProvisionError};
use fires_pen_core::sampler::{sample_loop, FrameSink, Framer, Imu, ImuSample, Outcome, TICK};
use fires_protocol::{Frame, FRAME_LEN};

static CLOCK: Mutex<()> = Mutex::new(());

/// Polls `fut` to completion, advancing mock time by `step` whenever it is pending.
fn run_mock<F: Future>(fut: F, step: Duration, limit: Duration) -> F::Output {
    let mut fut = pin!(fut);
    let mut cx = Context::from_waker(Waker::noop());
    let start = Instant::now();
    loop {
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return v;
        }
        assert!(Instant::now() - start < limit, "mock time limit reached");
        MockDriver::get().advance(step);
    }
}

// ---------------------------------------------------------------- sampler

/// An IMU whose readings encode the mock time at which each sensor was read.
struct ClockImu;

impl Imu for ClockImu {
    type Error = ();
    async fn read_all(&mut self) -> Result<ImuSample, ()> {
        let ms = |t: Instant| (t.as_millis() % 30_000) as i16;
        let accel = [ms(Instant::now()); 3];
        let gyro = [ms(Instant::now()); 3];
        let mag = [ms(Instant::now()); 3];
        Ok(ImuSample { accel, gyro, mag })
    }
}

/// A UART queue of `cap` frames that drains `per_tick` frames per tick.
struct Uart {
    queue: VecDeque<[u8; FRAME_LEN]>,
    cap: usize,
    wire: Vec<u8>,
}

impl FrameSink for Uart {
    fn try_send(&mut self, f: &[u8; FRAME_LEN]) -> bool {
        if self.queue.len() < self.cap {
            self.queue.push_back(*f);
            true
        } else {
            false
        }
    }
}

#[test]
fn sampler_ticks_every_10ms_with_whole_packet_drops() {
    let _g = CLOCK.lock().unwrap_or_else(|e| e.into_inner());
    MockDriver::get().reset();
    let mut uart = Uart {
        queue: VecDeque::new(),
        cap: 4,
        wire: Vec::new(),
    };
    let mut framer = Framer::new();
    let mut stamps = Vec::new();
    let mut outcomes = Vec::new();
    let mut imu = ClockImu;
    let fut = sample_loop(&mut imu, TICK, |r, at| {
        let s = r.unwrap();
        // all nine axes come from the tick's instant
        let tick_ms = (at.as_millis() % 30_000) as i16;
        assert!(s
            .accel
            .iter()
            .chain(&s.gyro)
            .chain(&s.mag)
            .all(|&v| v == tick_ms));
        stamps.push(at);
        outcomes.push(framer.sensor(&s, at.as_micros() as u32, &mut uart));
        // the radio stalls between ticks 20 and 40: nothing drains
        let n = stamps.len();
        if !(20..40).contains(&n) {
            while let Some(f) = uart.queue.pop_front() {
                uart.wire.extend_from_slice(&f);
            }
        }
        n < 100
    });
    run_mock(fut, Duration::from_millis(1), Duration::from_secs(5));
    assert_eq!(stamps.len(), 100);
    for w in stamps.windows(2) {
        assert_eq!(w[1] - w[0], Duration::from_millis(10), "one tick per 10 ms");
    }
    // the stall covers ticks 20..=39 and tick 40 sends before the queue drains: the queue takes 4 frames,
    // the other 17 are dropped whole
    let dropped: Vec<u8> = outcomes
        .iter()
        .filter_map(|o| match o {
            Outcome::Dropped(c) => Some(*c),
            _ => None,
        })
        .collect();
    assert_eq!(framer.dropped() as usize, dropped.len());
    assert_eq!(dropped.len(), 17);
    // the wire carries only whole frames, counters rising with gaps exactly at the drops
    assert_eq!(uart.wire.len() % FRAME_LEN, 0);
    let counters: Vec<u8> = uart
        .wire
        .chunks(FRAME_LEN)
        .map(|c| match Frame::parse(c.try_into().unwrap()).unwrap() {
            Frame::Sensor(p) => p.counter,
            Frame::Status(_) => unreachable!(),
        })
        .collect();
    assert_eq!(counters.len() + dropped.len(), 100);
    let mut all: Vec<u8> = counters.iter().chain(&dropped).copied().collect();
    all.sort();
    assert_eq!(all, (0..100).collect::<Vec<u8>>());
}

// ---------------------------------------------------------------- iWRAP provisioning

/// A scripted WT12: answers `AT`, accepts `SET`s (optionally rejecting one), switches rate on
/// `SET CONTROL BAUD`, reboots on `RESET`. Bytes sent at a rate the other side is not using arrive as garbage.
struct FakeWt12 {
    module_baud: u32,
    mcu_baud: u32,
    silent: bool,
    reject_once: Option<&'static str>,
    line: Vec<u8>,
    /// (arrival time, baud it was sent at, bytes)
    to_mcu: VecDeque<(Instant, u32, Vec<u8>)>,
    received: Vec<String>,
    resets: u32,
    /// Reboot (brown-out) when a line starting with this arrives, once.
    reboot_once: Option<&'static str>,
    deaf_until: Option<Instant>,
}

impl FakeWt12 {
    fn new(module_baud: u32) -> Self {
        FakeWt12 {
            module_baud,
            mcu_baud: 0,
            silent: false,
            reject_once: None,
            line: Vec::new(),
            to_mcu: VecDeque::new(),
            received: Vec::new(),
            resets: 0,
            reboot_once: None,
            deaf_until: None,
        }
    }

    fn reply(&mut self, after_ms: u64, text: &str) {
        self.to_mcu.push_back((
            Instant::now() + Duration::from_millis(after_ms),
            self.module_baud,
            text.as_bytes().to_vec(),
        ));
    }

    fn on_line(&mut self, line: String) {
        if self.deaf_until.is_some_and(|t| Instant::now() < t) {
            return;
        }
        self.received.push(line.clone());
        if line.is_empty() {
            return;
        }
        if let Some(prefix) = self.reboot_once {
            if line.starts_with(prefix) {
                self.reboot_once = None;
                self.deaf_until = Some(Instant::now() + Duration::from_millis(300));
                self.reply(300, "\r\nWRAP THOR AI (4.1.0 build 384)\r\nREADY.\r\n");
                return;
            }
        }
        if let Some(prefix) = self.reject_once {
            if line.starts_with(prefix) {
                self.reject_once = None;
                self.reply(2, "SYNTAX ERROR\r\n");
                return;
            }
        }
        if line == "AT" {
            self.reply(2, "OK\r\n");
        } else if let Some(rest) = line.strip_prefix("SET CONTROL BAUD ") {
            self.module_baud = rest.split(',').next().unwrap().parse().unwrap();
        } else if line == "RESET" {
            self.reply(400, "\r\nWRAP THOR AI (4.1.0 build 384)\r\nREADY.\r\n");
        } else if !line.starts_with("SET ") {
            self.reply(2, "SYNTAX ERROR\r\n");
        }
    }
}

impl ModemPort for FakeWt12 {
    type Error = ();
    async fn write_all(&mut self, bytes: &[u8]) -> Result<(), ()> {
        if self.silent {
            return Ok(());
        }
        if self.mcu_baud != self.module_baud {
            // the module sees noise and complains at its own rate
            self.line.clear();
            self.reply(3, "SYNTAX ERROR\r\n");
            return Ok(());
        }
        for &b in bytes {
            match b {
                b'\r' => {}
                b'\n' => {
                    let l = String::from_utf8(std::mem::take(&mut self.line)).unwrap();
                    self.on_line(l);
                }
                _ => self.line.push(b),
            }
        }
        Ok(())
    }

    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ()> {
        loop {
            let Some(&(at, _, _)) = self.to_mcu.front() else {
                Timer::after(Duration::from_secs(3600)).await;
                continue;
            };
            Timer::at(at).await;
            let (_, baud, bytes) = self.to_mcu.pop_front().unwrap();
            let bytes = if baud == self.mcu_baud {
                bytes
            } else {
                // what a UART at another rate makes of it
                bytes.iter().map(|b| b | 0x80).collect()
            };
            let n = bytes.len().min(buf.len());
            buf[..n].copy_from_slice(&bytes[..n]);
            if n < bytes.len() {
                self.to_mcu
                    .push_front((at, self.mcu_baud, bytes[n..].to_vec()));
            }
            return Ok(n);
        }
    }

    fn set_baud(&mut self, baud: u32) {
        self.mcu_baud = baud;
    }

    async fn reset_module(&mut self) {
        self.resets += 1;
        self.to_mcu.clear();
        Timer::after(Duration::from_millis(5)).await;
    }
}

#[test]
fn provisions_a_factory_module_answering_at_another_rate() {
    let _g = CLOCK.lock().unwrap_or_else(|e| e.into_inner());
    MockDriver::get().reset();
    let mut m = FakeWt12::new(115_200);
    let t0 = Instant::now();
    let r = run_mock(
        provision_module(&mut m, Config::FIRES),
        Duration::from_micros(500),
        Duration::from_secs(60),
    );
    assert_eq!(r, Ok(230_400));
    assert_eq!(m.module_baud, 230_400);
    let sets: Vec<&String> = m.received.iter().filter(|l| l.starts_with("SET")).collect();
    assert_eq!(sets.len(), 7);
    assert!(m.received.iter().any(|l| l == "SET BT AUTH * 1234"));
    assert!(m.received.iter().any(|l| l == "SET PROFILE SPP FIRES-Pen"));
    assert_eq!(m.received.last().unwrap(), "RESET");
    // garbage at 230400 is recognised at once, not after the probe timeout
    assert!(Instant::now() - t0 < Duration::from_secs(1));
}

#[test]
fn rejected_command_is_retried_after_backoff() {
    let _g = CLOCK.lock().unwrap_or_else(|e| e.into_inner());
    MockDriver::get().reset();
    let mut m = FakeWt12::new(230_400);
    m.reject_once = Some("SET CONTROL ESCAPE");
    let r = run_mock(
        provision_module(&mut m, Config::FIRES),
        Duration::from_micros(500),
        Duration::from_secs(60),
    );
    assert_eq!(r, Ok(230_400));
    let n = m
        .received
        .iter()
        .filter(|l| l.starts_with("SET CONTROL ESCAPE"))
        .count();
    assert_eq!(n, 2, "sent, rejected, sent again");
}

#[test]
fn silent_module_times_out_with_backoff_and_resets() {
    let _g = CLOCK.lock().unwrap_or_else(|e| e.into_inner());
    MockDriver::get().reset();
    let mut m = FakeWt12::new(115_200);
    m.silent = true;
    let t0 = Instant::now();
    let r = run_mock(
        provision_module(&mut m, Config::FIRES),
        Duration::from_millis(1),
        Duration::from_secs(120),
    );
    assert_eq!(r, Err(ProvisionError::NoResponse));
    assert_eq!(m.resets, 2);
    // 6 rounds of 3 probes of 300 ms, plus back-offs 200+400+800+1600+3200 ms (the 5 ms reset pulses fall
    // inside the back-offs)
    let expected = Duration::from_millis(6 * 3 * 300 + 6200);
    let took = Instant::now() - t0;
    assert!(
        took >= expected && took <= expected + Duration::from_millis(20),
        "took {took:?}"
    );
}

#[test]
fn module_rebooting_mid_configuration_is_recovered() {
    let _g = CLOCK.lock().unwrap_or_else(|e| e.into_inner());
    MockDriver::get().reset();
    let mut m = FakeWt12::new(230_400);
    // the module reboots (brown-out) on this command: it ignores the AT that follows and prints its banner
    // and an unsolicited READY. 300 ms later, while the provisioner waits for the OK
    m.reboot_once = Some("SET BT PAGEMODE");
    let r = run_mock(
        provision_module(&mut m, Config::FIRES),
        Duration::from_micros(500),
        Duration::from_secs(60),
    );
    assert_eq!(r, Ok(230_400));
    let n = m
        .received
        .iter()
        .filter(|l| l.starts_with("SET BT PAGEMODE"))
        .count();
    assert_eq!(n, 2, "the command lost to the reboot is sent again");
}
