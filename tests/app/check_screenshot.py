#!/usr/bin/env python3
"""Check a screenshot of the app: the right size, not blank, UI text in the left panel,
and the fabric in the 3D view (colour-mapped yarns, not just the background gradient).

usage: check_screenshot.py PNG WIDTH HEIGHT

Decodes the PNG with the standard library only (zlib + the five PNG row filters).
"""
import struct
import sys
import zlib


def read_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise SystemExit(f"{path}: not a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            if depth != 8 or colour not in (2, 6):
                raise SystemExit(f"{path}: expected 8-bit RGB/RGBA, got depth {depth} colour {colour}")
            bpp = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + ((a + b) >> 1)) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, bpp, rows


def main():
    path, want_w, want_h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    w, h, bpp, rows = read_png(path)
    if (w, h) != (want_w, want_h):
        raise SystemExit(f"{path}: {w}x{h}, expected {want_w}x{want_h}")

    def region(x0, y0, x1, y1, step=3):
        for y in range(int(y0), int(y1), step):
            row = rows[y]
            for x in range(int(x0), int(x1), step):
                yield row[x * bpp], row[x * bpp + 1], row[x * bpp + 2]

    # Layout of the app at this size (app/gui/cmd_gui.cpp): left panel 25 % of the width
    # (330..420 px), charts and status in the bottom 36 % (250..400 px).
    left = min(max(w * 0.25, 330), 420)
    bottom = min(max(h * 0.36, 250), 400)
    view = list(region(left + 20, 20, w - 20, h - bottom - 20))
    panel = list(region(10, 10, left - 10, h - 10))

    lum = [0.3 * r + 0.59 * g + 0.11 * b for r, g, b in view]
    mean = sum(lum) / len(lum)
    sd = (sum((v - mean) ** 2 for v in lum) / len(lum)) ** 0.5
    # The fabric is colour-mapped (turbo): either saturated, or at rest (the low end of the
    # map, a dark purple with red above green). The background gradient, the clamps, the
    # projectile and the caption are greys and grey-blues (red never above green).
    colourful = sum(1 for r, g, b in view if max(r, g, b) - min(r, g, b) > 90 or r > g + 12) / len(view)
    text = sum(1 for r, g, b in panel if min(r, g, b) > 170) / len(panel)
    print(f"{path}: {w}x{h}, view luminance {mean:.0f} +- {sd:.0f}, "
          f"colour-mapped fabric {100 * colourful:.1f} % of the view, panel text {100 * text:.2f} %")
    if sd < 8:
        raise SystemExit("FAIL: the 3D view is blank")
    if colourful < 0.05:
        raise SystemExit("FAIL: no colour-mapped fabric in the 3D view")
    if text < 0.005:
        raise SystemExit("FAIL: no UI text in the left panel")
    print("ok")


if __name__ == "__main__":
    main()
