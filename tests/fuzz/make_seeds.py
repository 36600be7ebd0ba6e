#!/usr/bin/env python3
"""Writes the committed seed corpora under tests/fuzz/corpus/<target>/.

Seeds are small valid and invalid examples of each input. Valid ones come from the real tools
where they exist (the e2e datasets and map in build/host/tests/e2e/, written by `./run test`;
pass --e2e DIR to use another folder) and are otherwise written here by hand, following
docs/*-format.md. Re-running replaces the generated files and leaves any other file alone (the
fuzzer's own finds may be merged in with `-merge=1`, see README.md).

usage: tests/fuzz/make_seeds.py [--e2e build/host/tests/e2e]
"""

import argparse
import hashlib
import os
import shutil
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CORPUS = os.path.join(HERE, "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 100 * 1024, (target, name)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def head_lines(path, n):
    with open(path, "rb") as f:
        return b"".join(f.readlines()[:n])


# --- map files (docs/map-format.md) -------------------------------------------------------------

def encode_map(width, height, thresholds, board_index, params, samples, pad=0):
    out = bytearray(b"HARMOMAP")
    out += struct.pack("<IIII", 1, width, height, len(thresholds))
    for h0, h1, s, v0, v1 in thresholds:
        out += struct.pack("<ffBBBB", h0, h1, s, v0, v1, pad)
    out += struct.pack("<II", len(samples), len(board_index))
    out += bytes(board_index)
    out += struct.pack("<6f", *params)
    for features, x, y in samples:
        out += struct.pack("<%df" % len(features), *features)
        out += struct.pack("<ff", x, y)
    out += struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF)
    return bytes(out)


def map_header(version, width, height, thresholds, board_index, params, samples):
    """The start every map version from 3 on shares: magic, frame size, thresholds, the sample
    and feature counts, the board index and the 7 model parameters."""
    out = bytearray(b"HARMOMAP")
    out += struct.pack("<IIII", version, width, height, len(thresholds))
    for h0, h1, s, v0, v1 in thresholds:
        out += struct.pack("<ffBBBB", h0, h1, s, v0, v1, 0)
    out += struct.pack("<II", len(samples), len(board_index))
    out += bytes(board_index)
    out += struct.pack("<7f", *params)
    return out


def encode_map_v3(width, height, thresholds, board_index, params, samples, forward):
    """Version 3: params gains the dissimilarity bound (7 floats); forward is None or
    (columns, rows, origin_x, origin_y, cell, sigmas, heading or None, expected rows, route)."""
    out = map_header(3, width, height, thresholds, board_index, params, samples)
    for features, x, y in samples:
        out += struct.pack("<%df" % len(features), *features)
        out += struct.pack("<ff", x, y)
    if forward is None:
        out += struct.pack("<II", 0, 0)
    else:
        cols, rows, ox, oy, cell, sigmas, heading, expected, route = forward
        out += struct.pack("<IIfffI", cols, rows, ox, oy, cell, len(sigmas))
        out += struct.pack("<%df" % len(sigmas), *sigmas)
        out += bytes([1 if heading else 0, 0, 0, 0])
        for cell_values in expected:
            out += struct.pack("<%df" % len(cell_values), *cell_values)
        out += struct.pack("<%df" % len(route), *route)
        if heading:
            out += struct.pack("<%df" % len(heading), *heading)
    out += struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF)
    return bytes(out)


def encode_map_v5(width, height, thresholds, board_index, params, weights, samples, forward,
                  calibration=(), bearings=None):
    """Version 5: feature weights after the params, the forward map's stored tiles (a bitmap
    over the tile grid, then their cells), the calibration entries. forward is (columns, rows,
    origin_x, origin_y, cell, sigmas, with_heading, stored tile positions, cell value function
    (tile, cell) -> (expected list, route, heading)). With bearings, version 6: bearings is
    (a1, a3, bearing sigmas, cell bearing function (tile, cell) -> list, 8.0 for none)."""
    out = map_header(5 if bearings is None else 6, width, height, thresholds, board_index, params,
                     samples)
    out += struct.pack("<%df" % len(weights), *weights)
    for features, x, y in samples:
        out += struct.pack("<%df" % len(features), *features)
        out += struct.pack("<ff", x, y)
    cols, rows, ox, oy, cell, sigmas, with_heading, tiles, value = forward
    out += struct.pack("<IIfffI", cols, rows, ox, oy, cell, len(sigmas))
    out += struct.pack("<%df" % len(sigmas), *sigmas)
    out += bytes([(1 if with_heading else 0) | (0 if bearings is None else 2), 0, 0, 0])
    positions = ((cols + 7) // 8) * ((rows + 7) // 8)
    bitmap = bytearray((positions + 7) // 8)
    for t in tiles:
        bitmap[t // 8] |= 1 << (t % 8)
    out += struct.pack("<I", len(tiles)) + bytes(bitmap)
    cells = [value(t, c) for t in sorted(tiles) for c in range(64)]
    for expected, _, _ in cells:
        out += struct.pack("<%df" % len(expected), *expected)
    for _, route, _ in cells:
        out += struct.pack("<f", route)
    if with_heading:
        for _, _, heading in cells:
            out += struct.pack("<f", heading)
    if bearings is not None:
        a1, a3, bearing_sigmas, bearing = bearings
        out += struct.pack("<ff", a1, a3)
        out += struct.pack("<%df" % len(bearing_sigmas), *bearing_sigmas)
        for t in sorted(tiles):
            for c in range(64):
                values = bearing(t, c)
                out += struct.pack("<%df" % len(values), *values)
    out += struct.pack("<I", len(calibration))
    for entry, v in calibration:
        out += struct.pack("<If", entry, v)
    out += struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF)
    return bytes(out)


def map_seeds(e2e):
    red = (340.0, 15.0, 110, 60, 255)
    green = (100.0, 145.0, 110, 60, 255)
    small = encode_map(160, 120, [red, green], [0, 1], [100.0 / 19200, 0.5, 0.7, 0.01, 0.02, 3.0],
                       [([0.0, 1.5], 2.1, 0.7), ([2.25, 0.5], 2.0, 1.3)])
    one = encode_map(2, 2, [red], [0], [1.0, 1.0, 1.0, 0.0, 0.0, 1.0], [([0.0], 0.0, 0.0)])
    seeds = {
        "small.hmap": small,
        "one-sample.hmap": one,
        "truncated.hmap": small[:40],
        "bad-magic.hmap": b"HARMOMAX" + small[8:],
        "bad-version.hmap": small[:8] + struct.pack("<I", 2) + small[12:],
        "bad-crc.hmap": small[:-1] + bytes([small[-1] ^ 0xFF]),
        "trailing.hmap": encode_map(2, 2, [red], [0], [1.0, 1.0, 1.0, 0.0, 0.0, 1.0],
                                    [([0.0], 0.0, 0.0)])[:-4] + b"\0\0\0\0" + b"\0\0\0\0",
        "empty.hmap": b"",
        "text.hmap": b"this is not a map, it is a text file saying so\n",
        "forward-v3.hmap": encode_map_v3(
            160, 120, [red, green], [0, 1], [100.0 / 19200, 0.5, 0.7, 0.01, 0.02, 3.0, 0.1],
            [([0.0, 1.5], 2.1, 0.7), ([2.25, 0.5], 2.0, 1.3)],
            (2, 2, 2.0, 0.7, 0.05, [0.1, 0.2], [1.5, 1.6, 1.4, 1.7],
             [[0.0, 1.5], [0.5, 1.2], [1.0, 1.0], [2.25, 0.5]], [0.0, 0.02, 0.03, 0.0])),
        "no-forward-v3.hmap": encode_map_v3(
            2, 2, [red], [0], [1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.5], [([0.0], 0.0, 0.0)], None),
        # A 20 x 10 grid (3 x 2 tiles) of which two tiles are stored, with a calibration.
        "forward-v5-sparse.hmap": encode_map_v5(
            160, 120, [red, green], [0, 1], [100.0 / 19200, 0.5, 0.7, 0.01, 0.02, 3.0, 0.1],
            [1.0, 0.5], [([0.0, 1.5], 2.1, 0.7), ([2.25, 0.5], 2.0, 1.3)],
            (20, 10, 2.0, 0.7, 0.05, [0.1, 0.2], True, [1, 3],
             lambda t, c: ([0.01 * c, 1.5 - 0.01 * t], 0.001 * c, 1.5)),
            [(1, 0.02), (2, 0.03), (3, 0.01)]),
        # Version 6: the same with board bearings, the second board's at every third cell
        # missing (8.0).
        "forward-v6-bearings.hmap": encode_map_v5(
            160, 120, [red, green], [0, 1], [100.0 / 19200, 0.5, 0.7, 0.01, 0.02, 3.0, 0.1],
            [1.0, 0.5], [([0.0, 1.5], 2.1, 0.7), ([2.25, 0.5], 2.0, 1.3)],
            (20, 10, 2.0, 0.7, 0.05, [0.1, 0.2], True, [1, 3],
             lambda t, c: ([0.01 * c, 1.5 - 0.01 * t], 0.001 * c, 1.5)),
            [(1, 0.02), (2, 0.03), (3, 0.01)],
            (1.1, -0.12, [0.04, 0.08],
             lambda t, c: [-3.0 + 0.09 * c, 8.0 if c % 3 == 0 else 0.5 - 0.01 * c - 0.1 * t])),
    }
    tiny = os.path.join(e2e, "tiny.hmap")
    if os.path.exists(tiny):
        with open(tiny, "rb") as f:
            seeds["tiny-trained.hmap"] = f.read()
    for target in ("map_decode", "map_roundtrip"):
        for name, data in seeds.items():
            put(target, name, data)


# --- firmware config (docs/config-format.md) ----------------------------------------------------

def config_seeds(e2e):
    with open(os.path.join(ROOT, "docs", "examples", "harmoloc.toml"), "rb") as f:
        put("config", "example.toml", f.read())
    put("config", "empty.toml", "")
    put("config", "cycle.toml", "[cycle]\nrate_hz = 30\nbudget_ms = 15.0\n"
        "camera_timeout_ms = 250\nencoder_timeout_ms = 250\n")
    put("config", "boards.toml",
        '[[board]]\nname = "red"\nhue_deg = [340, 15]\nsaturation_min = 110\nvalue_min = 60\n'
        'value_max = 255\n\n[[board]]\nname = "cyan"\nhue_deg = [170.5, 200]\n')
    put("config", "odometry-can.toml",
        "[odometry]\nwheel_radius_m = 0.05\ntrack_m = 0.3\nticks_per_rev = 4096\n"
        "left_direction = 1\nright_direction = -1\n\n"
        '[can]\ninterface = "can1"\nencoder_id = 0x181\nlength = 4\nleft_offset = 0\n'
        'right_offset = 2\ncounter_bits = 16\nbyte_order = "big"\n')
    put("config", "filter-link-rt.toml",
        "[filter]\nparticles = 512\nseed = 7\nalpha = [0.1, 0.01, 0.1, 0.01]\nfix_sigma_m = 0.4\n"
        "outlier_probability = 0.05\nresample_threshold = 0.5\ninit_position_sigma_m = 0.05\n"
        "vision_only_speed_mps = 0.3\n\n[link]\nsystem_id = 1\ncomponent_id = 197\n"
        "baud = 115200\nheartbeat_hz = 1.0\n\n[realtime]\nenabled = false\npriority = 80\n"
        "cpu = -1\nlock_memory = false\nprefault_stack_kb = 256\n")
    bad = {
        "syntax.toml": "[cycle\nrate_hz = 30\n",
        "typo.toml": "[cycle]\nrate_hz = 30\nbudget_sm = 15\n",
        "range.toml": "[filter]\nparticles = 100000\n",
        "rt.toml": "[realtime]\npriority = 120\n",
        "type.toml": '[cycle]\nrate_hz = "fast"\n',
        "board-not-table.toml": "board = [1, 2]\n",
        "hue.toml": "[[board]]\nhue_deg = [400, nan]\n",
    }
    for name, text in bad.items():
        put("config", "bad-" + name, text)


# --- dataset metadata (docs/dataset-format.md) --------------------------------------------------

METADATA = """format_version = 1
name = "seed"
seed = 1

[camera]
width_px = 160
height_px = 120
pixel_format = "rgb24"
rate_hz = 30
frames_index = "frames.csv"

[encoders]
log = "encoders.log"
interface = "can0"
can_id = 0x181
length = 8
left_offset = 0
right_offset = 4
counter_bits = 32
byte_order = "little"

[robot]
wheel_radius_m = 0.05
track_m = 0.3
ticks_per_rev = 4096
left_direction = 1
right_direction = 1

[ground_truth]
file = "groundtruth.tum"
"""


def metadata_seeds(e2e):
    put("metadata", "good.toml", METADATA)
    put("metadata", "yuyv-16bit.toml",
        METADATA.replace('"rgb24"', '"yuyv"').replace("length = 8", "length = 4")
        .replace("right_offset = 4", "right_offset = 2").replace("counter_bits = 32",
                                                                  "counter_bits = 16")
        .replace('"little"', '"big"').replace("left_direction = 1", "left_direction = -1"))
    put("metadata", "minimal.toml", "format_version = 1\n[camera]\nwidth_px = 2\nheight_px = 2\n"
        "rate_hz = 1\n[robot]\nwheel_radius_m = 0.001\ntrack_m = 0.001\nticks_per_rev = 1\n")
    put("metadata", "bad-version.toml", METADATA.replace("format_version = 1", "format_version = 2"))
    put("metadata", "bad-odd-yuyv.toml",
        METADATA.replace('"rgb24"', '"yuyv"').replace("width_px = 160", "width_px = 161"))
    put("metadata", "bad-layout.toml", METADATA.replace("right_offset = 4", "right_offset = 2"))
    put("metadata", "bad-syntax.toml", "format_version = 1\n[camera\n")
    put("metadata", "gpio.toml", METADATA.replace('[encoders]\n', '[encoders]\nsource = "gpio"\n')
        .replace('log = "encoders.log"', 'log = "encoders.csv"'))
    put("metadata", "bad-source.toml",
        METADATA.replace('[encoders]\n', '[encoders]\nsource = "quadrature"\n'))
    for sub in ("train", "wrap16"):
        p = os.path.join(e2e, sub, "metadata.toml")
        if os.path.exists(p):
            shutil.copyfile(p, os.path.join(CORPUS, "metadata", "e2e-%s.toml" % sub))


# --- frame index, PPM headers -------------------------------------------------------------------

def frame_index_seeds(e2e):
    put("frame_index", "good.csv", "timestamp_ns,file\n1767225600000000000,frames/000000.ppm\n"
        "1767225600033333333,frames/000001.ppm\n1767225600066666666,frames/000002.yuv\n")
    put("frame_index", "crlf-comments.csv",
        "timestamp_ns,file\r\n# a comment\r\n\r\n1,a.ppm\r\n2,b/c.ppm\r\n")
    put("frame_index", "no-header.csv", "10,x.ppm\n20,y.ppm\n")
    put("frame_index", "empty.csv", "")
    put("frame_index", "bad-order.csv", "timestamp_ns,file\n2,a.ppm\n1,b.ppm\n")
    put("frame_index", "bad-escape.csv", "timestamp_ns,file\n1,../outside.ppm\n2,/abs.ppm\n")
    put("frame_index", "bad-stamp.csv", "timestamp_ns,file\n99999999999999999999,a.ppm\n-1,b\n")
    put("frame_index", "bad-nocomma.csv", "timestamp_ns,file\n1 a.ppm\n")
    p = os.path.join(e2e, "train", "frames.csv")
    if os.path.exists(p):
        put("frame_index", "e2e-train.csv", head_lines(p, 40))

    put("ppm_header", "good.ppm", b"P6\n160 120\n255\n" + bytes(48))
    put("ppm_header", "comments.ppm", b"P6 # made by hand\n# another\n2\t1\r255 " + bytes(6))
    put("ppm_header", "bad-p3.ppm", b"P3\n1 1\n255\n0 0 0\n")
    put("ppm_header", "bad-16bit.ppm", b"P6\n1 1\n65535\n" + bytes(6))
    put("ppm_header", "bad-zero.ppm", b"P6\n0 1\n255\n")
    put("ppm_header", "bad-huge.ppm", b"P6\n1000001 1\n255\n")
    put("ppm_header", "bad-truncated.ppm", b"P6\n160 12")
    put("ppm_header", "bad-nows.ppm", b"P6\n1 1\n255")
    frame = os.path.join(e2e, "train", "frames", "000000.ppm")
    if os.path.exists(frame):
        with open(frame, "rb") as f:
            put("ppm_header", "e2e-frame-head.ppm", f.read(64))


# --- candump logs -------------------------------------------------------------------------------

def candump_seeds(e2e):
    lines = {
        "std.txt": "(1767225600.000000) can0 181#0011223344556677",
        "ext.txt": "(1767225600.010000) vcan1 1FFFFFFF#DEADBEEF",
        "empty-data.txt": "(0.000001) can0 7FF#",
        "crlf.txt": "(12.345678)  can0  123#00FF \r",
        "bad-fd.txt": "(1.000000) can0 181##0112233",
        "bad-rtr.txt": "(1.000000) can0 181#R",
        "bad-odd.txt": "(1.000000) can0 181#001",
        "bad-stamp.txt": "(1.00000) can0 181#00",
        "bad-id.txt": "(1.000000) can0 800#00",
        "bad-iface.txt": "(1.000000)can0",
    }
    for name, line in lines.items():
        put("candump_line", name, line)
    log = "".join(l + "\n" for n, l in lines.items() if not n.startswith("bad"))
    put("candump_log", "mixed.log", log)
    put("candump_log", "empty.log", "")
    put("candump_log", "bad-line.log", log + "garbage\n")
    for sub in ("train", "wrap16"):
        p = os.path.join(e2e, sub, "encoders.log")
        if os.path.exists(p):
            put("candump_log", "e2e-%s.log" % sub, head_lines(p, 40))


# --- GPIO encoder recordings (encoders.csv) -----------------------------------------------------

def encoder_csv_seeds(e2e):
    """Each seed: 1 byte choosing the counter width (8 + b % 25 bits), then the file."""
    header = "timestamp_ns,left_ticks,right_ticks\n"
    width = {8: 0, 16: 8, 32: 24}
    files = {
        "good-32.csv": (32, header + "1767225600000000000,0,0\n1767225600033333333,27,-3\n"
                        "1767225600066666666,55,4294967290\n"),
        "good-16-wrap.csv": (16, header + "100,65500,-10\n200,65535,-32768\n300,12,65535"),
        "good-8-crlf.csv": (8, header.replace("\n", "\r\n") + "1,255,-128\r\n2,0,0\r\n"),
        "bad-order.csv": (32, header + "200,1,2\n100,1,2\n"),
        "bad-width.csv": (16, header + "100,65536,0\n"),
        "bad-blank.csv": (32, header + "100,1,2\n\n200,1,2\n"),
        "bad-fields.csv": (32, header + "100,1\n"),
        "bad-header.csv": (32, "t,l,r\n100,1,2\n"),
        "header-only.csv": (32, header),
    }
    for name, (bits, text) in files.items():
        put("encoder_csv", name, bytes([width[bits]]) + text.encode())
    p = os.path.join(e2e, "gpio", "encoders.csv")
    if os.path.exists(p):
        put("encoder_csv", "e2e-test.csv", bytes([width[32]]) + head_lines(p, 40))
    p = os.path.join(e2e, "gpio", "encoders16.csv")
    if os.path.exists(p):
        put("encoder_csv", "e2e-wrap16.csv", bytes([width[16]]) + head_lines(p, 40))


# --- TUM ----------------------------------------------------------------------------------------

def tum_seeds(e2e):
    put("tum", "good.tum", "# t x y z qx qy qz qw\n"
        "1767225600.000000 2.106169 0.701242 0 0 0 0.773745255 0.633496867\n"
        "1767225600.033333 2.106169 0.701242 0 0 0 0.773745255 0.633496867\n\n"
        "1767225600.066667 2.2 0.8 0 0 0 -0.5 0.866\n")
    put("tum", "tabs-exp.tum", "\t1e0\t-1.5E-3 2 3 0 0 0 1\r\n2 +0 -0 0 0 0 1 0\n")
    put("tum", "empty.tum", "")
    put("tum", "bad-fields.tum", "1 2 3 4 5 6 7\n")
    put("tum", "bad-extra.tum", "1 2 3 4 5 6 7 8 9\n")
    put("tum", "bad-order.tum", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")
    put("tum", "bad-inf.tum", "1 inf 0 0 0 0 0 1\n2 1e999 0 0 0 0 0 1\n")
    for name in ("groundtruth.tum", "labels.tum"):
        p = os.path.join(e2e, "train", name)
        if os.path.exists(p):
            put("tum", "e2e-" + name, head_lines(p, 40))


# --- scenario files (docs/scenarios.md) ---------------------------------------------------------

def scenario_seeds(e2e):
    with open(os.path.join(ROOT, "docs", "scenarios.md")) as f:
        doc = f.read()
    start = doc.index("```toml\n") + len("```toml\n")
    put("scenario", "docs-example.toml", doc[start:doc.index("```", start)])
    put("scenario", "empty.toml", "")
    put("scenario", "tiny-wrap16.toml", 'base = "tiny-wrap16"\nname = "w"\n[encoders]\n'
        "counter_bits = 16\ninitial_left = 65000\n")
    put("scenario", "boards.toml",
        'base = "tiny"\n[[boards]]\nname = "a"\ncolour = [1, 2, 3]\ncentre = [1, 2, 0.5]\n'
        "size = [0.2, 0.3]\nfacing_deg = -90\n\n[[boards]]\ncolour = [255, 255, 0]\n"
        "centre = [2, 2.5, 1]\nsize = [0.5, 0.5]\n")
    put("scenario", "bad-typo.toml", 'base = "tiny"\n[camera]\nwidht_px = 320\n')
    put("scenario", "bad-base.toml", 'base = "no-such-scenario"\n')
    put("scenario", "bad-odd.toml", "[camera]\nwidth_px = 161\n")
    put("scenario", "bad-waypoints.toml", "[route]\nwaypoints = [[1, 2]]\n")
    put("scenario", "bad-colour.toml", "[[boards]]\ncolour = [256, 0, 0]\ncentre = [0, 0, 0]\n"
        "size = [1, 1]\n")
    # Events (docs/scenarios.md, "Events"): the documented example, and broken ones.
    start = doc.index("```toml\n", doc.index("## Events")) + len("```toml\n")
    put("scenario", "docs-events.toml", doc[start:doc.index("```", start)])
    put("scenario", "events.toml",
        'base = "tiny"\n[[occluders]]\nname = "p"\ncolour = [40, 40, 50]\nradius_m = 0.2\n'
        "height_m = 1.7\npath = [[1, 0.5, 2], [2.5, 3.5, 2]]\n\n[[board_moves]]\n"
        'board = "green"\nat_s = 3\noffset_m = [0.1, 0, 0]\nturn_deg = 5\n\n[kidnaps]\n'
        "count = 2\nfirst_s = 1\ninterval_s = 3\nmin_distance_m = 0.4\n")
    put("scenario", "bad-event-board.toml",
        '[[board_moves]]\nboard = "purple"\nat_s = 1\noffset_m = [0.3, 0, 0]\n')
    put("scenario", "bad-event-path.toml", "[[occluders]]\npath = [[2, 1, 1], [1, 2, 2]]\n")
    put("scenario", "bad-event-kidnaps.toml", "[kidnaps]\ncount = 3\nevery_s = 2\n")
    p = os.path.join(e2e, "train", "scenario.toml")
    if os.path.exists(p):
        shutil.copyfile(p, os.path.join(CORPUS, "scenario", "e2e-train.toml"))


# --- segmentation frames (layout in segment_fuzz.cpp) -------------------------------------------

def segment_seed(yuyv, boards, width, height, stride, pixels):
    head = bytes([(boards << 1) | (1 if yuyv else 0)]) + struct.pack("<HHH", width, height, stride)
    windows = [(340, 15, 110, 60, 255), (100, 145, 110, 60, 255), (215, 250, 110, 60, 255),
               (45, 70, 110, 60, 255), (285, 320, 110, 60, 255), (170, 200, 110, 60, 255),
               (0, 360, 0, 0, 255), (180, 180, 255, 255, 255)]
    for h0, h1, s, v0, v1 in windows:
        head += struct.pack("<HHBBB", h0 * 20, h1 * 20, s, v0, v1)
    return head + pixels


def segment_seeds(e2e):
    rgb = bytes([220, 30, 30, 30, 180, 40, 30, 60, 220, 230, 210, 30, 200, 40, 190, 30, 190, 200,
                 0, 0, 0, 255, 255, 255]) * 4
    put("segment", "rgb-8x4.bin", segment_seed(False, 6, 8, 4, 24, rgb[:96]))
    put("segment", "rgb-odd-stride.bin", segment_seed(False, 8, 3, 5, 11, bytes(range(0, 255, 5))))
    yuyv = bytes([81, 90, 81, 240, 145, 54, 145, 34, 41, 240, 41, 110, 16, 128, 235, 128]) * 4
    put("segment", "yuyv-8x4.bin", segment_seed(True, 6, 8, 4, 16, yuyv))
    put("segment", "yuyv-odd.bin", segment_seed(True, 3, 5, 2, 12, yuyv[:24]))
    put("segment", "zero-stride.bin", segment_seed(False, 1, 4, 100, 0, rgb[:12]))
    put("segment", "empty.bin", segment_seed(True, 0, 0, 0, 0, b""))


# --- the link's inbound side (mavlink_inbound_fuzz.cpp) ------------------------------------------

FUZZ_KEY = bytes((11 + 31 * i) & 0xFF for i in range(32))  # make_key(11) in the target
FUZZ_BASE_TS = 1000000000
CRC_EXTRA = {0: 50, 76: 152, 77: 143, 111: 34, 253: 83, 331: 91}


def x25(data, crc=0xFFFF):
    for b in data:
        t = (b ^ crc) & 0xFF
        t = (t ^ (t << 4)) & 0xFF
        crc = ((crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4)) & 0xFFFF
    return crc


def mav_frame(msg_id, payload, sysid=255, compid=190, key=None, ts=0, link_id=0):
    payload = payload.rstrip(b"\0") or b"\0"
    f = bytes([0xFD, len(payload), 1 if key else 0, 0, 0, sysid, compid,
               msg_id & 0xFF, (msg_id >> 8) & 0xFF, msg_id >> 16]) + payload
    crc = x25(bytes([CRC_EXTRA[msg_id]]), x25(f[1:]))
    f += struct.pack("<H", crc)
    if key:
        f += bytes([link_id]) + struct.pack("<Q", ts)[:6]
        f += hashlib.sha256(key + f).digest()[:6]
    return f


def command_long(cmd, params=(), target=(1, 197), **kw):
    p = struct.pack("<7fHBBB", *(list(params) + [0.0] * 7)[:7], cmd, target[0], target[1], 0)
    return mav_frame(76, p, **kw)


def timesync(tc1, ts1, target=(0, 0), **kw):
    return mav_frame(111, struct.pack("<qqBB", tc1, ts1, target[0], target[1]), **kw)


def mavlink_seeds(e2e):
    hb = mav_frame(0, bytes([0, 0, 0, 0, 6, 8, 0, 0, 3]))
    pose = (2.0, -1.0, 0.5, 0.01, 0.01)
    garbage = bytes([0xFD, 33, 0, 0, 0, 255, 190, 76, 0, 0, 0x55, 0xFD, 0x00, 0x13, 0xFE]) * 3
    # Raw mode (bit 1 clear); bits 2-4 pick how many bytes a read delivers.
    put("mavlink_inbound", "raw-unsigned.bin", bytes([0x00 | 5 << 2]) + garbage +
        command_long(31011, pose) + hb + command_long(512, [0]) + command_long(31010))
    put("mavlink_inbound", "raw-signed.bin", bytes([0x01 | 4 << 2]) +
        command_long(31011, pose, key=FUZZ_KEY, ts=FUZZ_BASE_TS + 5) + garbage +
        command_long(512, [331], key=FUZZ_KEY, ts=FUZZ_BASE_TS + 6) +
        command_long(512, [331], key=FUZZ_KEY, ts=FUZZ_BASE_TS + 6) +  # replayed
        command_long(31010, key=FUZZ_KEY, ts=FUZZ_BASE_TS + 9, sysid=42) +
        command_long(31010, key=bytes(32), ts=FUZZ_BASE_TS + 10) + command_long(400))
    put("mavlink_inbound", "raw-one-byte-reads.bin", bytes([0x01]) +
        command_long(31011, pose, key=FUZZ_KEY, ts=FUZZ_BASE_TS + 1, link_id=2))
    put("mavlink_inbound", "raw-stalled-false-start.bin", bytes([0x00 | 6 << 2]) +
        bytes([0xFD, 233, 0, 0, 0, 1, 1, 0x4B, 0x01, 0]) + command_long(31010))
    # TIMESYNC: requests to everyone and to us from an autopilot (1/1), an answer (tc1 != 0), one
    # to another system; signed: a good one, a replay and one with the wrong key.
    put("mavlink_inbound", "raw-timesync.bin", bytes([0x00 | 5 << 2]) +
        timesync(0, 123456789, sysid=1, compid=1) + timesync(0, 5, (1, 197), sysid=1, compid=1) +
        timesync(77, 5, sysid=1, compid=1) + timesync(0, 6, (2, 0)) + command_long(31010))
    signed = timesync(0, 42, sysid=1, compid=1, key=FUZZ_KEY, ts=FUZZ_BASE_TS + 3)
    put("mavlink_inbound", "raw-timesync-signed.bin", bytes([0x01 | 4 << 2]) + signed + signed +
        timesync(0, 43, sysid=1, compid=1, key=bytes(32), ts=FUZZ_BASE_TS + 4))
    # Structured mode: ops 0 raw, 1 command, 2 other message, 3 replay, 4 truncated, 5 false start.
    prog = bytes([
        1, 0x00, 0x01, 1, 0xC0, 0, 0x3F, 0, 0x00, 0x00, 0, 0, 0, 0, 0, 1, 0x10, 0x00,  # set pose
        3,                                     # the same again
        0, 8, 1, 2, 3, 0xFD, 5, 6, 7, 8,       # raw bytes
        2, 0, 9, 1, 2, 3, 4, 5, 6, 7, 8, 9, 3,  # a HEARTBEAT, signed
        1, 0x08, 0x02, 2, 0x15, 0, 0, 0, 0, 0, 0, 0x01, 0x20, 0x00,  # request message to comp 0
        5, 3, 10, 0,                           # a false start
        1, 0x02, 0x00, 0, 0, 0, 0, 0, 0, 0, 0x03, 0x30, 0x00,         # wrong key, from 42
        4, 20,                                 # half of it
        1, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0x31, 0x00, 0x00,         # stale timestamp
    ])
    put("mavlink_inbound", "structured-signed.bin", bytes([0x03 | 3 << 2]) + prog)
    put("mavlink_inbound", "structured-unsigned.bin", bytes([0x02 | 6 << 2]) + prog)


# --- large and deeply nested inputs (issue 16) ---------------------------------------------------

def area_log_seeds(e2e):
    head = ("# harmoloc area log v1: pixels of each board per frame\n"
            "# width_px=320 height_px=240 thresholds_crc32=0x1c2d3e4f\n")
    put("area_log", "v1.csv", head + "timestamp_ns,red,green\n100,1,2\n200,3,4\n")
    put("area_log", "distrust.csv",
        head + "timestamp_ns,red,green,distrusted_mask\n100,1,2,0\n200,3,4,2\n")
    cols = ("timestamp_ns,red,green,distrusted_mask,column_sum_red,column_sum_green,"
            "side_px_red,side_px_green\n")
    put("area_log", "columns.csv",
        head + cols + "100,10,20,0,1500,3190,0,2\n200,0,76800,1,0,12249600,0,480\n"
        "300,5,5,0,-,-,-,-\n")
    put("area_log", "bad-columns.csv", head + cols + "100,1,2,0,320,0,0,0\n100,1,2,0,-,1,0,0\n")
    if e2e:
        p = os.path.join(e2e, "areas.csv")
        if os.path.exists(p):
            put("area_log", "e2e-areas.csv", head_lines(p, 40))


def large_structure_seeds(e2e):
    """The shapes of the adversarial probe: TOML nested past the 32-level bound (dotted keys,
    table headers, arrays, inline tables) and just within it, and long lines, in each TOML
    format; candump logs out of time order; a map whose training target is at 1e30 m."""
    deep = {
        "deep-dotted-33.toml": ".".join(["a"] * 33) + " = 1\n",
        "deep-dotted-32.toml": ".".join(["a"] * 32) + " = 1\n",
        "deep-dotted-5000.toml": ".".join(["a"] * 5000) + " = 1\n",
        "deep-header.toml": "[" + ".".join(["t"] * 40) + "]\nx = 1\n",
        "deep-arrays.toml": "x = " + "[" * 40 + "]" * 40 + "\n",
        "deep-inline.toml": "x = " + "{a = " * 20 + "1" + "}" * 20 + "\n",
        "deep-mixed.toml": "[a.b.c]\nd.e = [{f.g = [[{h = 1}]]}]\n",
        "long-comment.toml": "# " + "x" * 60000 + "\n",
        "long-string.toml": 'name = "' + "y" * 60000 + '"\n',
        "many-keys.toml": "".join("k%d = %d\n" % (i, i) for i in range(3000)),
    }
    for target in ("config", "metadata", "scenario"):
        for name, text in deep.items():
            put(target, name, text)
    put("candump_log", "bad-past-line.log",
        "(1.000000) can0 181#00\n(1.010000) can0 181#01\n(0.500000) can0 181#02\n")
    put("candump_log", "bad-future-line.log",
        "(1.000000) can0 181#00\n(99999.010000) can0 181#01\n(1.020000) can0 181#02\n")
    put("candump_log", "same-time.log", "(1.000000) can0 181#00\n(1.000000) can0 281#01\n")
    red = (340.0, 15.0, 110, 60, 255)
    for target in ("map_decode", "map_roundtrip"):
        put(target, "far-target.hmap",
            encode_map(2, 2, [red], [0], [1.0, 1.0, 1.0, 0.0, 0.0, 1.0], [([0.0], 1e30, 0.0)]))
        put(target, "edge-target.hmap",
            encode_map(2, 2, [red], [0], [1.0, 1.0, 1.0, 0.0, 0.0, 1.0], [([0.0], 1e4, -1e4)]))


# --- the MAVLink signing state (docs/wire-protocol.md, "Signing") --------------------------------

def signing_state_seeds(e2e):
    head = "harmoloc-signing-state 1\n"
    put("signing_state", "fresh.state", head + "high_water 12000000\n")
    put("signing_state", "streams.state", head + "high_water 281474976710655\n" +
        "".join("stream %d 190 %d %d\n" % (255 - i, i % 3, 1000 + i) for i in range(32)))
    put("signing_state", "bad-header.state", "harmoloc-signing-state 2\nhigh_water 5\n")
    put("signing_state", "bad-number.state", head + "high_water banana\n")
    put("signing_state", "bad-stream.state", head + "high_water 5\nstream 1 2 3 6\n")
    put("signing_state", "empty.state", "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--e2e", default=os.path.join(ROOT, "build", "host", "tests", "e2e"),
                    help="folder with the e2e datasets and tiny.hmap (optional)")
    args = ap.parse_args()
    if not os.path.isdir(args.e2e):
        print("note: %s not found: only the hand-written seeds" % args.e2e, file=sys.stderr)
    for make in (map_seeds, config_seeds, metadata_seeds, frame_index_seeds, candump_seeds,
                 encoder_csv_seeds, tum_seeds, scenario_seeds, segment_seeds, mavlink_seeds,
                 large_structure_seeds, signing_state_seeds, area_log_seeds):
        make(args.e2e)
    total = 0
    for d, _, files in os.walk(CORPUS):
        for f in files:
            total += os.path.getsize(os.path.join(d, f))
    print("corpus: %d bytes in %s" % (total, CORPUS))


if __name__ == "__main__":
    main()
