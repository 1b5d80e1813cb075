//! Power policy: IDLE auto-off after two minutes without activity (thesis App. B) and the long-press shutdown.
//!
//! The pen's supply is held on by the MCU (hardware-docs/board.md, power latch): pressing the power button
//! switches the regulator on through the latch's diode, firmware then holds `PWR_HOLD` high; releasing
//! `PWR_HOLD` turns the pen off. This module only decides *when*.

use embassy_time::{Duration, Instant};

/// IDLE time without activity after which the pen turns itself off.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(120);

/// Why the pen turns off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerOffReason {
    /// Two minutes in IDLE without a button, command or link event.
    IdleTimeout,
    /// The power button was held for the long-press time.
    LongPress,
    /// The battery stayed below [`CRITICAL_BATTERY_MV`].
    LowBattery,
}

/// Below this (filtered) voltage the status packet's low-battery flag is set.
pub const LOW_BATTERY_MV: u16 = 3_450;
/// Below this (filtered) voltage the pen turns itself off before the 3.3 V regulator drops out.
pub const CRITICAL_BATTERY_MV: u16 = 3_300;
/// Readings below this are ignored as implausible (the 3.3 V regulator could not be running): an unconnected
/// divider must not turn the pen off.
pub const MIN_PLAUSIBLE_MV: u16 = 2_500;
/// Divider between VBAT and the ADC pin (board.md: 100 kΩ / 100 kΩ).
pub const BATTERY_DIVIDER: u32 = 2;
/// Internal reference voltage of the STM32F103, mV (datasheet typical).
pub const VREFINT_MV: u32 = 1_200;

/// Battery voltage in mV from one ADC reading of the divided battery and one of VREFINT, which makes the result
/// independent of the exact 3.3 V rail. Returns 0 when the reference reads 0 (ADC not working).
pub fn battery_mv(raw_battery: u16, raw_vrefint: u16) -> u16 {
    if raw_vrefint == 0 {
        return 0;
    }
    let mv = u32::from(raw_battery) * VREFINT_MV * BATTERY_DIVIDER / u32::from(raw_vrefint);
    mv.min(u32::from(u16::MAX)) as u16
}

/// Low-pass filtered battery voltage and its thresholds; fed about once per second.
#[derive(Clone, Copy, Debug, Default)]
pub struct BatteryMonitor {
    /// Filtered value in mV × 8 (fixed point), 0 before the first reading.
    filtered_x8: u32,
}

impl BatteryMonitor {
    /// No reading yet.
    pub const fn new() -> Self {
        BatteryMonitor { filtered_x8: 0 }
    }

    /// Adds a reading (mV); the first one initialises the filter, later ones move it by 1/8 (motor and radio
    /// current spikes are smoothed over ~8 s).
    pub fn update(&mut self, mv: u16) {
        if mv < MIN_PLAUSIBLE_MV {
            return;
        }
        let x8 = u32::from(mv) * 8;
        self.filtered_x8 = if self.filtered_x8 == 0 {
            x8
        } else {
            self.filtered_x8 - self.filtered_x8 / 8 + x8 / 8
        };
    }

    /// Filtered voltage, mV (0 = no reading).
    pub fn mv(&self) -> u16 {
        (self.filtered_x8 / 8) as u16
    }

    /// Whether the low-battery flag is due.
    pub fn low(&self) -> bool {
        self.filtered_x8 != 0 && self.mv() < LOW_BATTERY_MV
    }

    /// Whether the pen must turn off.
    pub fn critical(&self) -> bool {
        self.filtered_x8 != 0 && self.mv() < CRITICAL_BATTERY_MV
    }
}

/// The IDLE auto-off timer.
#[derive(Clone, Copy, Debug)]
pub struct AutoOff {
    last_activity: Instant,
}

impl AutoOff {
    /// Starts counting at `now`.
    pub fn new(now: Instant) -> Self {
        AutoOff { last_activity: now }
    }

    /// Something happened: restart the count.
    pub fn activity(&mut self, now: Instant) {
        if now > self.last_activity {
            self.last_activity = now;
        }
    }

    /// When the pen turns off if it stays idle.
    pub fn deadline(&self) -> Instant {
        self.last_activity + IDLE_TIMEOUT
    }

    /// Whether the pen, idle (`idle` = not streaming), must turn off at `now`. Streaming restarts the count.
    pub fn expired(&mut self, idle: bool, now: Instant) -> bool {
        if !idle {
            self.activity(now);
            return false;
        }
        now >= self.deadline()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn battery_conversion_and_filter() {
        // VREFINT 1.2 V reads 1489 at a 3.3 V rail; 1.85 V at the pin (3.7 V battery) reads 2296
        assert_eq!(battery_mv(2296, 1489), 3700);
        assert_eq!(battery_mv(100, 0), 0);
        let mut b = BatteryMonitor::new();
        assert!(!b.low() && !b.critical() && b.mv() == 0);
        b.update(0); // divider not fitted
        b.update(1200);
        assert!(!b.critical() && b.mv() == 0);
        b.update(3700);
        assert_eq!(b.mv(), 3700);
        // a single dip (motor start) does not trip the flags
        b.update(2600);
        assert!(!b.low());
        for _ in 0..40 {
            b.update(3400);
        }
        assert!(b.low() && !b.critical());
        for _ in 0..40 {
            b.update(3200);
        }
        assert!(b.critical());
    }

    #[test]
    fn two_minutes_of_idle() {
        let t0 = Instant::from_secs(10);
        let mut a = AutoOff::new(t0);
        assert!(!a.expired(true, t0 + Duration::from_secs(119)));
        a.activity(t0 + Duration::from_secs(60));
        assert!(!a.expired(true, t0 + Duration::from_secs(179)));
        assert!(a.expired(true, t0 + Duration::from_secs(180)));
        // streaming keeps it alive, and the count restarts when streaming stops
        assert!(!a.expired(false, t0 + Duration::from_secs(500)));
        assert!(!a.expired(true, t0 + Duration::from_secs(619)));
        assert!(a.expired(true, t0 + Duration::from_secs(620)));
    }
}
