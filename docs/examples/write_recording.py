#!/usr/bin/env python3
"""Writes a minimal FIRES recording (format 1.0, docs/recording.md) with no ground truth.

usage: write_recording.py OUT_DIR
"""
import json, math, os, struct, sys

out = sys.argv[1]
for d in ("cam0", "cam1"):
    os.makedirs(os.path.join(out, d), exist_ok=True)

def camera(tx):  # 640x480, 60 deg hFOV, no distortion; x_cam = R x_world + t
    f = 320 / math.tan(math.radians(30))
    return {"intrinsics": {"width": 640, "height": 480, "fx": f, "fy": f, "cx": 319.5, "cy": 239.5,
                           "k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0, "k3": 0.0},
            "extrinsics": {"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "translation_m": [tx, 0, 0]}}

meta = {"format": "fires-recording", "format_version": "1.0",
        "source": {"kind": "hardware", "scenario": None, "seed": None, "generator": "write_recording.py"},
        "rig": {"cameras": [camera(0.0), camera(-0.06)]},
        "pen": {"led_positions_m": [0.0, 0.07, 0.11, 0.16], "tip_offset_m": 0.02},
        "scale_factors": {"accel_mps2_per_count": 9.80665 / 1024, "gyro_radps_per_count": 0.07 * math.pi / 180,
                          "mag_tesla_per_count": 1e-7},
        "link": {"baud": 230400, "sample_rate_hz": 100},
        "cameras": [{"id": 0, "provides": "blobs", "nominal_rate_hz": 15.0},
                    {"id": 1, "provides": "images", "nominal_rate_hz": 15.0}],
        "has_truth": False}
with open(os.path.join(out, "meta.json"), "w") as f:
    json.dump(meta, f, indent=2)

def sensor_packet(counter, accel, gyro, mag):  # 22 bytes: sync 0x20 0x0A, counter, 9 x i16 LE, XOR
    body = struct.pack("<BBB9h", 0x20, 0x0A, counter & 0xFF, *accel, *gyro, *mag)
    x = 0
    for b in body:
        x ^= b
    return body + bytes([x])

with open(os.path.join(out, "link.bin"), "wb") as f:  # records: u64 LE host ns, u32 LE length, bytes
    for i in range(10):
        data = sensor_packet(i, (0, 1024, 0), (0, 0, 0), (200, -50, 400))
        f.write(struct.pack("<QI", 1_000_000_000 + i * 10_000_000, len(data)) + data)

with open(os.path.join(out, "cam0", "frames.jsonl"), "w") as f:
    blobs = [{"x": 300.25, "y": 200.5, "area": 12.0, "intensity": 255.0}]
    f.write(json.dumps({"camera": 0, "index": 0, "exposure_time_ns": 1_010_000_000, "blobs": blobs}) + "\n")

pixels = bytearray([12]) * (640 * 480)
pixels[200 * 640 + 300] = 255
with open(os.path.join(out, "cam1", "000000.pgm"), "wb") as f:  # binary PGM, maxval 255
    f.write(b"P5\n640 480\n255\n" + bytes(pixels))
with open(os.path.join(out, "cam1", "frames.jsonl"), "w") as f:
    f.write(json.dumps({"camera": 1, "index": 0, "exposure_time_ns": 1_030_000_000, "image": "000000.pgm"}) + "\n")
