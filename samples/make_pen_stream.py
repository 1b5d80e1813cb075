#!/usr/bin/env python3
"""Writes samples/pen-stream.bin: 5 s of a pen at rest being turned slowly, as the FIRES link carries it, with the
faults a real link shows. It is also a worked example of an encoder written from hardware-docs/protocol.md alone.

Faults (the expected `fires decode` summary is in host/tests/decode_cli.rs):
  - 40 bytes of module chatter before the first packet (iWRAP's boot banner);
  - sensor packets 100, 101 and 350 never arrive (whole packets dropped);
  - packets 200 and 420 arrive with one corrupted byte each;
  - packet 300 loses one byte;
  - packet 250 arrives twice (a radio retransmission).
Run: python3 samples/make_pen_stream.py samples/pen-stream.bin
"""
import math
import struct
import sys


def xor(data):
    x = 0
    for b in data:
        x ^= b
    return x


def sensor(counter, accel, gyro, mag):
    body = bytes([0x20, 0x0A, counter & 0xFF]) + struct.pack("<9h", *accel, *gyro, *mag)
    return body + bytes([xor(body)])


def status(sequence, sensor_counter, time_us, buttons=0, flags=0b1011, health=0x3F, reason=0,
           battery_mv=3950, dropped=0, fw=(0, 1), proto=1):
    body = bytes([0x20, 0x0B, sequence & 0xFF, sensor_counter & 0xFF]) + struct.pack("<I", time_us & 0xFFFFFFFF)
    body += bytes([buttons, flags, health, reason]) + struct.pack("<HI", battery_mv, dropped)
    body += bytes([fw[0], fw[1], proto])
    return body + bytes([xor(body)])


def main(path):
    g_counts = 1024  # LIS3LV02DL at +-2 g: 1024 counts per g (hardware-docs/protocol.md, scale factors)
    out = bytearray(b"WRAP THOR AI (4.1.0 build 435)\r\nREADY.\r\n"[:40])
    seq = 0
    for i in range(500):
        t = i / 100.0
        tilt = 0.3 * math.sin(2 * math.pi * 0.2 * t)  # slow rocking about the pen's y axis
        accel = (round(-g_counts * math.sin(tilt)), 0, round(g_counts * math.cos(tilt)))
        rate = 0.3 * 2 * math.pi * 0.2 * math.cos(2 * math.pi * 0.2 * t)  # rad/s
        gyro = (0, round(math.degrees(rate) / 0.070), 0)  # 70 mdps per count
        mag = (round(200 * math.cos(tilt)), 0, round(-430 + 200 * math.sin(tilt)))  # 0.1 uT per count
        packet = bytearray(sensor(i, accel, gyro, mag))
        if i in (100, 101, 350):
            continue
        if i in (200, 420):
            packet[7] ^= 0x10
        if i == 300:
            del packet[9]
        out += packet
        if i == 250:
            out += packet
        if i % 100 == 99:
            out += status(seq, i, i * 10_000, reason=0)
            seq += 1
    with open(path, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "pen-stream.bin")
