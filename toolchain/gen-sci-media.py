#!/usr/bin/env python3
"""Generates board/sim/sci_media: small synthetic "preoperative images" for the SCI's
image viewer (ct/, xray/, mri/; 8-bit grey PNG, 160x160) and a patient record text
file. Standard library only; the same bytes every run. Usage:
    toolchain/gen-sci-media.py [OUT_DIR]   (default board/sim/sci_media)
"""
import math
import os
import struct
import sys
import zlib


def png_grey(path, w, h, pixel):
    rows = b"".join(b"\x00" + bytes(pixel(x, y) for x in range(w)) for y in range(h))
    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)
    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def clamp(v):
    return max(0, min(255, int(v)))


def ct(k):
    # An axial slice: body ellipse, spine, two kidneys moving with the slice index.
    def px(x, y):
        u, v = (x - 80) / 70, (y - 80) / 55
        if u * u + v * v > 1:
            return 0
        val = 90
        if (x - 80) ** 2 + (y - 118) ** 2 < 12 ** 2:
            val = 240
        for side in (-1, 1):
            if ((x - 80 - side * (32 + 3 * k)) / 13) ** 2 + ((y - 95) / 18) ** 2 < 1:
                val = 140
        return clamp(val + 8 * math.sin(x * 0.3 + k) * math.cos(y * 0.25))
    return px


def xray(k):
    # A chest film: dark lungs, bright ribs and mediastinum.
    def px(x, y):
        val = 200
        for side in (-1, 1):
            if ((x - 80 - side * 35) / 30) ** 2 + ((y - 80) / 55) ** 2 < 1:
                val = 60
        if abs(x - 80) < 12 + k * 2:
            val = 220
        if val == 60 and int((y + 4 * abs(x - 80) / 10) / 14) % 2 == 0 and (y % 14) < 4:
            val = 170
        return val
    return px


def mri(k):
    # A brain slice: skull ring, grey matter, ventricles.
    def px(x, y):
        r = math.hypot((x - 80) / 65, (y - 80) / 72)
        if r > 1:
            return 0
        if r > 0.9:
            return 230
        val = 120 + 40 * math.sin(r * 18 + k)
        if ((x - 80) / (8 + 3 * k)) ** 2 + ((y - 75) / 20) ** 2 < 1:
            val = 30
        return clamp(val)
    return px


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "board", "sim", "sci_media")
    for name, make, count in (("ct", ct, 3), ("xray", xray, 2), ("mri", mri, 3)):
        d = os.path.join(out, name)
        os.makedirs(d, exist_ok=True)
        for k in range(count):
            png_grey(os.path.join(d, "%s_%02d.png" % (name, k + 1)), 160, 160, make(k))
    record = os.path.join(out, "patient_record.txt")
    with open(record + ".tmp", "w") as f:
        # app/media's patient record format (patient_record.hpp).
        f.write("# synthetic test record\n"
                "name: SIM Patient\n"
                "id: SIM-0001\n"
                "birth_date: 1970-01-01\n"
                "procedure: laparoscopic cholecystectomy\n"
                "notes: diagnosis: symptomatic cholelithiasis\n"
                "notes: allergies: penicillin\n"
                "notes: CT 2026-10-02: gallstones, no duct dilatation\n")
    os.replace(record + ".tmp", record)


if __name__ == "__main__":
    main()
