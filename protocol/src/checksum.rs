//! Checksums of the wire format.
//!
//! Packets (pen -> host) use the thesis's XOR checksum (FIRES thesis, App. B): byte 21 is the XOR of
//! bytes 0..=20. XOR detects every single-byte error, which is the fault the radio produces most.
//! Extended commands (host -> pen) carry a CRC-8 (polynomial 0x07, init 0x00, "CRC-8/SMBUS"), which detects every
//! burst of up to 8 bits, so every corrupted character of a hex-encoded command frame.

/// XOR of all bytes: the sensor/status packet checksum.
#[inline]
pub fn xor(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |acc, b| acc ^ b)
}

/// CRC-8/SMBUS (poly 0x07, init 0, no reflection, no final XOR) of `bytes`.
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc8_matches_the_published_check_value() {
        // The catalogue check value of CRC-8/SMBUS over ASCII "123456789".
        assert_eq!(crc8(b"123456789"), 0xF4);
    }

    #[test]
    fn xor_of_a_packet_with_its_checksum_is_zero() {
        let mut p = [0u8; 22];
        for (i, b) in p.iter_mut().enumerate() {
            *b = (i as u8).wrapping_mul(37);
        }
        p[21] = xor(&p[..21]);
        assert_eq!(xor(&p), 0);
    }
}
