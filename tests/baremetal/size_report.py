#!/usr/bin/env python3
"""Size and stack report of the Cortex-M7 kernel build (docs/performance.md, "Co-processor build").

Reads a built tests/baremetal tree and writes a Markdown report:
  - per kernel: text/data/bss of its object file (arm-none-eabi-size) and what of it the test
    program keeps after --gc-sections (the link map), and what the link discards;
  - per entry point: its own frame (-fstack-usage), the deepest chain through our code
    (-fcallgraph-info), the libm calls at the leaves, and the stack measured on the emulated
    core (the test program paints the stack around each call);
  - the static state at the default capacities (sizeof on the target) against 256 KiB of TCM.

  size_report.py --build build/baremetal --emulator tests/baremetal/qemu-mps2-an500.sh \\
                 [--out build/baremetal/size-report.md]
"""
import argparse
import glob
import os
import re
import subprocess
import sys
import tempfile

TCM_BYTES = 256 * 1024
TOOL_PREFIX = "arm-none-eabi-"
KERNEL_LIB = "libharmoloc_kernels.a"


def tool(name, *args):
    return subprocess.run([TOOL_PREFIX + name, *args], capture_output=True, text=True,
                          check=True).stdout


def demangle(names):
    if not names:
        return {}
    out = subprocess.run([TOOL_PREFIX + "c++filt"], input="\n".join(names), capture_output=True,
                         text=True, check=True).stdout.splitlines()
    return dict(zip(names, out))


def kib(n):
    return f"{n / 1024:.1f} KiB"


def object_sizes(build):
    """text/data/bss of each member of the kernel library (everything compiled)."""
    rows = {}
    for line in tool("size", os.path.join(build, KERNEL_LIB)).splitlines()[1:]:
        parts = line.split()
        if len(parts) >= 6 and parts[5].endswith(".obj"):
            rows[parts[5]] = tuple(int(p) for p in parts[:3])
    return rows


SECTION_ONE_LINE = re.compile(r"^ (\.\S+)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
SECTION_NAME = re.compile(r"^ (\.\S+)$")
SECTION_REST = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")


def map_sections(path):
    """(kept, discarded): lists of (section, size, file) from a GNU ld map."""
    kept, discarded = [], []
    part = None
    pending = None
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("Discarded input sections"):
                part = discarded
                continue
            if line.startswith("Memory Configuration"):
                part = None
                continue
            if line.startswith("Linker script and memory map"):
                part = kept
                continue
            if part is None:
                continue
            m = SECTION_ONE_LINE.match(line)
            if m:
                part.append((m.group(1), int(m.group(3), 16), m.group(4)))
                pending = None
                continue
            m = SECTION_NAME.match(line)
            if m:
                pending = m.group(1)
                continue
            m = SECTION_REST.match(line)
            if m and pending:
                part.append((pending, int(m.group(2), 16), m.group(3)))
            pending = None
    return kept, discarded


def kind_of(section):
    for prefix, kind in ((".text", "text"), (".rodata", "rodata"), (".data", "data"),
                         (".bss", "bss")):
        if section == prefix or section.startswith(prefix + "."):
            return kind
    return None


def member(file):
    m = re.search(r"\(([^()]+)\)$", file)
    return m.group(1) if m else file


def linked_sizes(kept):
    """Bytes kept per kernel object and per outside library (libm, libgcc, libc...)."""
    per = {}
    for section, size, file in kept:
        kind = kind_of(section)
        if kind is None or size == 0:
            continue
        if KERNEL_LIB + "(" in file:
            key = member(file)
        else:
            m = re.search(r"/(lib[^/()]+\.a)\(", file)
            key = m.group(1) if m else "program (tests, start-up)"
        per.setdefault(key, {"text": 0, "rodata": 0, "data": 0, "bss": 0})[kind] += size
    return per


def discarded_kernel_functions(discarded):
    names = []
    for section, size, file in discarded:
        if KERNEL_LIB + "(" in file and section.startswith(".text.") and size > 0:
            names.append((section[len(".text."):], size, member(file)))
    pretty = demangle([n for n, _, _ in names])
    return [(pretty.get(n, n), size, obj) for n, size, obj in names]


CI_NODE = re.compile(r'^node: \{ title: "([^"]+)" label: "([^"]*)"')
CI_EDGE = re.compile(r'^edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
CI_BYTES = re.compile(r"\\n(\d+) bytes \((static|dynamic|dynamic,bounded)\)")


def call_graph(build):
    """Frames and edges of the kernels from the .ci files (-fcallgraph-info=su)."""
    frames, qualifiers, labels, edges = {}, {}, {}, {}
    for path in glob.glob(os.path.join(build, "CMakeFiles", "harmoloc_kernels.dir", "**", "*.ci"),
                          recursive=True):
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = CI_NODE.match(line)
                if m:
                    title, label = m.group(1), m.group(2)
                    b = CI_BYTES.search(label)
                    if b:
                        frames[title] = int(b.group(1))
                        qualifiers[title] = b.group(2)
                        labels[title] = label.split("\\n")[0]
                    continue
                m = CI_EDGE.match(line)
                if m:
                    edges.setdefault(m.group(1), set()).add(m.group(2))
    return frames, qualifiers, labels, edges


def deepest(fn, frames, edges, memo, active=()):
    """(bytes, chain, outside calls) of the deepest call chain from fn through our code."""
    if fn in memo:
        return memo[fn]
    if fn in active:  # recursion: none today; reported rather than looped on
        return (0, [fn + " (recursive)"], set())
    own = frames.get(fn, 0)
    best = (0, [], set())
    outside = set()
    for callee in edges.get(fn, ()):
        if callee in frames:
            sub = deepest(callee, frames, edges, memo, active + (fn,))
            outside |= sub[2]
            if sub[0] > best[0]:
                best = sub
        else:
            outside.add(callee)
    result = (own + best[0], [fn] + best[1], outside)
    memo[fn] = result
    return result


def target_info(emulator, elf):
    proc = subprocess.run([emulator, elf], capture_output=True, text=True, timeout=300,
                          check=False)
    if proc.returncode != 0:
        sys.exit(f"{elf} failed on the emulated core (status {proc.returncode})")
    info = {}
    for line in proc.stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0] == "i":
            info[parts[1].split(".", 1)[1]] = int(parts[2])
    return info


def static_objects(elf):
    """The test program's large static objects: (name, size, section letter)."""
    rows = []
    for line in tool("nm", "-C", "--size-sort", "-S", elf).splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "bBdD" and int(parts[1], 16) >= 1024:
            rows.append((parts[3], int(parts[1], 16), "bss" if parts[2] in "bB" else "data"))
    return sorted(rows, key=lambda r: -r[1])


# Entry points to report stack for: (label, mangled-name pattern, measured key).
ENTRY_POINTS = [
    ("crc32", r"^_ZN8harmoloc10algorithms5crc32E", "stack.crc32"),
    ("apply_arc", r"^_ZN8harmoloc10algorithms9apply_arcE", "stack.apply_arc_x1000"),
    ("odometry_from_ticks", r"^_ZN8harmoloc10algorithms19odometry_from_ticksE", None),
    ("decode_encoder_frame", r"^_ZN8harmoloc10algorithms20decode_encoder_frameE", None),
    ("BoardClassifier::build", r"^_ZN8harmoloc10algorithms15BoardClassifier5buildE",
     "stack.classifier_build"),
    ("segment_rgb24 (classifier)",
     r"^_ZN8harmoloc10algorithms13segment_rgb24E.*RKNS0_15BoardClassifierE",
     "stack.segment_rgb24"),
    ("segment_yuyv (classifier)",
     r"^_ZN8harmoloc10algorithms12segment_yuyvE.*RKNS0_15BoardClassifierE", "stack.segment_yuyv"),
    ("areas_to_features", r"^_ZN8harmoloc10algorithms17areas_to_featuresE", None),
    ("harmonic_query", r"^_ZN8harmoloc10algorithms14harmonic_queryE",
     "stack.harmonic_query_4096x8"),
    ("ParticleFilter::predict", r"^_ZN8harmoloc10algorithms14ParticleFilter7predictE",
     "stack.pf_predict"),
    ("ParticleFilter::update_position",
     r"^_ZN8harmoloc10algorithms14ParticleFilter15update_positionE", "stack.pf_update_position"),
    ("ParticleFilter::resample_if_needed",
     r"^_ZN8harmoloc10algorithms14ParticleFilter18resample_if_neededE", "stack.pf_resample"),
    ("ParticleFilter::estimate", r"^_ZNK8harmoloc10algorithms14ParticleFilter8estimateE",
     "stack.pf_estimate"),
    ("decode_map", r"^_ZN8harmoloc10algorithms10decode_mapE", "stack.decode_map"),
    ("locate (forward map)", r"^_ZN8harmoloc10algorithms6locateE", None),
    ("BoardReliability::assess",
     r"^_ZN8harmoloc10algorithms16BoardReliability6assessE", "stack.board_assess"),
    ("ParticleFilter::update_boards",
     r"^_ZN8harmoloc10algorithms14ParticleFilter13update_boardsE", "stack.pf_update_boards"),
    ("KidnapDetector::step", r"^_ZN8harmoloc10algorithms14KidnapDetector4stepE", None),
]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", required=True)
    parser.add_argument("--emulator", required=True)
    parser.add_argument("--out")
    args = parser.parse_args()
    build = args.build
    elf = os.path.join(build, "kernel_tests.elf")

    objects = object_sizes(build)
    kept, discarded = map_sections(elf + ".map")
    linked = linked_sizes(kept)
    # Every entry point linked alone, against libm and libgcc only (check_freestanding.sh).
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                     "check_freestanding.sh"), TOOL_PREFIX + "g++",
                        os.path.join(build, KERNEL_LIB), tmp], check=True,
                       stdout=subprocess.DEVNULL)
        alone = linked_sizes(map_sections(os.path.join(tmp, "kernels-alone.elf.map"))[0])
    frames, qualifiers, _, edges = call_graph(build)
    info = target_info(args.emulator, elf)
    lines = []
    w = lines.append

    w("# Cortex-M7 kernel build: sizes and stack\n")
    w("Generated by tests/baremetal/size_report.py from the build in "
      f"`{os.path.relpath(build)}` (arm-none-eabi-gcc "
      f"{tool('gcc', '-dumpversion').strip()}, -O2, Cortex-M7 fpv5-d16 hard float).\n")

    w("## Code per kernel\n")
    w("Compiled: the object file (`arm-none-eabi-size`; its text includes read-only data). "
      "Linked alone: every exported function but the host-side map encoder, with libm and "
      "libgcc only (`check_freestanding.sh`), after `--gc-sections`. In the tests: what the test "
      "program keeps, which calls the online entry points only (no colour tables).\n")
    w("| kernel | compiled text | data | bss | linked alone: code | rodata | data+bss "
      "| in the tests: code+rodata |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|")
    empty = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    total = [0] * 7
    for obj in sorted(objects):
        t, d, b = objects[obj]
        a = alone.get(obj, empty)
        l = linked.get(obj, empty)
        row = [t, d, b, a["text"], a["rodata"], a["data"] + a["bss"], l["text"] + l["rodata"]]
        total = [x + y for x, y in zip(total, row)]
        w(f"| {obj.replace('.cpp.obj', '')} | " + " | ".join(str(x) for x in row) + " |")
    w("| **all kernels** | " + " | ".join(f"**{x}**" for x in total) + " |")
    for lib in ("libm.a", "libgcc.a"):
        if lib in alone:
            a = alone[lib]
            w(f"| {lib} (what the kernels call) | | | | {a['text']} | {a['rodata']} | "
              f"{a['data'] + a['bss']} | |")
    w("")
    gone = discarded_kernel_functions(discarded)
    if gone:
        w("Compiled but not in the test program (no online caller; `--gc-sections` drops them):\n")
        for name, size, obj in sorted(gone, key=lambda g: (g[2], g[0])):
            w(f"- `{name}` ({size} B, {obj.replace('.cpp.obj', '')})")
        w("")

    w("## Stack per entry point\n")
    w("Own frame from `-fstack-usage`; deepest chain through our code from "
      "`-fcallgraph-info=su` (libm's frames are not in it); measured: the high-water mark on the "
      "emulated core, libm included, from painting the stack around one call.\n")
    w("| entry point | own frame | deepest chain (our code) | libm/libgcc calls | measured |")
    w("|---|---:|---:|---|---:|")
    memo = {}
    for label, pattern, key in ENTRY_POINTS:
        names = [n for n in frames if re.search(pattern, n)]
        if not names:
            continue
        fn = names[0]
        depth, chain, outside = deepest(fn, frames, edges, memo)
        calls = ", ".join(sorted(c for c in outside if not c.startswith("_Z"))) or "-"
        q = "" if qualifiers.get(fn) == "static" else f" ({qualifiers.get(fn)})"
        measured = str(info[key]) if key and key in info else "-"
        w(f"| {label} | {frames[fn]}{q} | {depth} | {calls} | {measured} |")
    w("")

    w("## Static state at the default capacities (sizeof on the Cortex-M7)\n")
    sizes = {k[len("sizeof_"):]: v for k, v in info.items() if k.startswith("sizeof_")}
    w("| object | bytes | KiB | share of 256 KiB |")
    w("|---|---:|---:|---:|")
    for name, size in sorted(sizes.items(), key=lambda kv: -kv[1]):
        w(f"| {name} | {size} | {size / 1024:.1f} | {100.0 * size / TCM_BYTES:.0f}% |")
    w("")
    w("The test program's static objects as linked (`nm -S`; data = initialised, in the load "
      "image as well as in RAM):\n")
    for name, size, where in static_objects(elf):
        w(f"- `{name}`: {size} B in .{where}")
    w("")

    query_stack = info.get("stack.harmonic_query_4096x8", 0)
    model = sizes.get("HarmonicModel", 0)
    forward = sizes.get("ForwardMap", 0)
    pf = sizes.get("ParticleFilter", 0)
    cls = sizes.get("BoardClassifier", 0)
    code = total[3] + total[4] + sum(alone.get(lib, empty)["text"] + alone.get(lib, empty)["rodata"]
                                     for lib in ("libm.a", "libgcc.a"))
    w("## Against 256 KiB of TCM/SRAM\n")
    w("| configuration | bytes | fits |")
    w("|---|---:|---|")
    pf_stack = max(info.get(k, 0) for k in info if k.startswith("stack.pf_"))
    configs = [
        ("kernel code + libm + libgcc (linked alone)", code),
        ("map (4096 x 8) + harmonic query stack + classifier + code",
         model + query_stack + cls + code),
        ("particle filter (4096) + its deepest stack + code",
         pf + max(info.get(k, 0) for k in info if k.startswith("stack.pf_")) + code),
        ("forward map (its tile capacity, 8 boards) + particle filter (4096) + stack + code",
         forward + pf + max(info.get(k, 0) for k in info if k.startswith("stack.pf_")) + code),
        ("map + forward map + particle filter + classifier + query stack + code",
         model + forward + pf + cls + query_stack + code),
        # The filter's arrays are sized by kMaxParticles (particles, scratch, weights, and the
        # KLD bin table and its slot list: 74 bytes a particle, all of sizeof but a few bytes);
        # a co-processor build for the default 1024 particles would set it so.
        ("forward map + particle filter of capacity 1024 (computed) + stack + code",
         forward + (pf - (pf // 4096) * (4096 - 1024)) + pf_stack + code),
    ]
    for label, size in configs:
        w(f"| {label} | {size} ({kib(size)}) | {'yes' if size <= TCM_BYTES else 'no'} "
          f"({100.0 * size / TCM_BYTES:.0f}%) |")
    w("")

    text = "\n".join(lines) + "\n"
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
