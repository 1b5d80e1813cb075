//! Register access over I2C or SPI, with the sub-address conventions of the parts on the board.
//!
//! - ST parts (LIS3LV02DL, L3G4200D) on I2C: bit 7 of the sub-address asks for auto-increment on multi-byte reads.
//! - ST parts on 4-wire SPI: first byte bit 7 = read, bit 6 = auto-increment (MS), bits 5..0 = address.
//! - MAG3110 (I2C only): auto-increment is always on, the sub-address is sent as is.

use embedded_hal_async::i2c::I2c;
use embedded_hal_async::spi::{Operation, SpiDevice};

/// Byte-register access to one sensor.
#[allow(async_fn_in_trait)] // single-threaded embedded executors: no Send bound needed
pub trait RegisterBus {
    /// Error of the underlying bus.
    type Error;
    /// Writes one register.
    async fn write_register(&mut self, reg: u8, value: u8) -> Result<(), Self::Error>;
    /// Reads `buf.len()` consecutive registers starting at `reg`.
    async fn read_registers(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Self::Error>;
    /// Reads one register.
    async fn read_register(&mut self, reg: u8) -> Result<u8, Self::Error> {
        let mut b = [0u8];
        self.read_registers(reg, &mut b).await?;
        Ok(b[0])
    }
}

/// A sensor on an I2C bus at a 7-bit address.
#[derive(Debug)]
pub struct I2cRegisters<I> {
    i2c: I,
    address: u8,
    /// OR-ed into the sub-address of multi-byte reads.
    auto_increment: u8,
}

impl<I> I2cRegisters<I> {
    /// An ST MEMS part (sub-address bit 7 = auto-increment).
    pub fn st(i2c: I, address: u8) -> Self {
        I2cRegisters {
            i2c,
            address,
            auto_increment: 0x80,
        }
    }
    /// A part that auto-increments on its own (MAG3110).
    pub fn plain(i2c: I, address: u8) -> Self {
        I2cRegisters {
            i2c,
            address,
            auto_increment: 0,
        }
    }
    /// Gives the bus back.
    pub fn release(self) -> I {
        self.i2c
    }
}

impl<I: I2c> RegisterBus for I2cRegisters<I> {
    type Error = I::Error;
    async fn write_register(&mut self, reg: u8, value: u8) -> Result<(), I::Error> {
        self.i2c.write(self.address, &[reg, value]).await
    }
    async fn read_registers(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), I::Error> {
        let sub = if buf.len() > 1 {
            reg | self.auto_increment
        } else {
            reg
        };
        self.i2c.write_read(self.address, &[sub], buf).await
    }
}

/// An ST MEMS part on a 4-wire SPI device (chip select handled by the `SpiDevice`).
#[derive(Debug)]
pub struct SpiRegisters<S> {
    spi: S,
}

/// SPI read bit of the ST command byte.
const SPI_READ: u8 = 0x80;
/// SPI auto-increment (MS) bit of the ST command byte.
const SPI_MULTI: u8 = 0x40;

impl<S> SpiRegisters<S> {
    /// Wraps the device.
    pub fn new(spi: S) -> Self {
        SpiRegisters { spi }
    }
    /// Gives the device back.
    pub fn release(self) -> S {
        self.spi
    }
}

impl<S: SpiDevice> RegisterBus for SpiRegisters<S> {
    type Error = S::Error;
    async fn write_register(&mut self, reg: u8, value: u8) -> Result<(), S::Error> {
        self.spi.write(&[reg & 0x3F, value]).await
    }
    async fn read_registers(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), S::Error> {
        let multi = if buf.len() > 1 { SPI_MULTI } else { 0 };
        let cmd = [SPI_READ | multi | (reg & 0x3F)];
        self.spi
            .transaction(&mut [Operation::Write(&cmd), Operation::Read(buf)])
            .await
    }
}
