//! FIRES smart-pen firmware core: everything the pen does that does not touch a register of the MCU.
//!
//! The embassy application (`firmware/app`) is thin glue that binds these pieces to the STM32F103VE's
//! peripherals. Everything here is `no_std`, allocation-free and tested on the host:
//!
//! - [`drivers`]: LIS3LV02DL, L3G4200D and MAG3110 register drivers over `embedded-hal-async` I2C or SPI.
//! - [`sampler`]: the 100 Hz scheduler and framing: one sensor packet per tick, whole-packet drops, counters.
//! - [`status`]: status packets (once per second, on button changes, on request).
//! - [`iwrap`]: the WT12's iWRAP reply/event parser and the provisioning state machine.
//! - [`commands`]: the pen's mode controller (`=`, `:`, extended commands, link events).
//! - [`buttons`], [`status_led`], [`power`], [`feedback`]: debounce and long press, LED patterns, IDLE auto-off,
//!   vibration and beep queue.
//! - [`board`]: the board description the host needs (scale factors, rates).
//!
//! Timing is expressed with `embassy_time::{Instant, Duration}`; the state machines take `now` explicitly, and the
//! few async loops are tested with embassy-time's mock driver (tests/mock_time.rs).
#![no_std]

pub mod board;
pub mod buttons;
pub mod commands;
pub mod drivers;
pub mod feedback;
pub mod iwrap;
pub mod power;
pub mod sampler;
pub mod status;
pub mod status_led;
