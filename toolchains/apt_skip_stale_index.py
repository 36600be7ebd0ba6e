#!/usr/bin/env python3
"""Stops apt from fetching one architecture's index of the suites whose index for it failed.

Used by ./run after `dpkg --add-architecture ARCH` when `apt-get update` fails on that
architecture's Packages index of some suite only (a mirror serving a stale file: on 2026-11-21
bookworm-security's binary-armhf/Packages.xz had the wrong size). Each such suite's entry in the
apt sources gets `Architectures-Remove: ARCH` (deb822 .sources) or `arch-=ARCH` (one-line .list),
so apt-get update succeeds again and ARCH's packages come from the other suites (for Debian 12:
the main suite, whose point releases carry the security fixes too). Nothing else changes; any
other failure in the log makes it change nothing and exit 1.

  apt_skip_stale_index.py ARCH UPDATE_LOG [--etc DIR] [--dry-run]

Exit status: 0 changed (or would change) the sources, 1 the log has other failures or no
matching source entry was found, 2 bad usage.
"""
import argparse
import glob
import os
import re
import sys

FAILED = re.compile(r"^E: Failed to fetch (\S+)")
INDEX_URL = re.compile(r"^(?P<uri>.+?)/dists/(?P<suite>[^/]+)/(?P<comp>.+)/binary-(?P<arch>[^/]+)/")
HARMLESS_E = re.compile(r"^E: Some index files failed to download")
MARK = "harmoloc ./run: this suite's {arch} index was stale on the mirror (apt-get update failed)"


def norm(uri):
    return uri.rstrip("/")


def failed_suites(log_text, arch):
    """(uri, suite) pairs whose ARCH index failed; None if anything else failed."""
    suites, other = set(), []
    for line in log_text.splitlines():
        m = FAILED.match(line)
        if m:
            idx = INDEX_URL.match(m.group(1))
            if idx and idx.group("arch") == arch:
                suites.add((norm(idx.group("uri")), idx.group("suite")))
            else:
                other.append(line)
        elif line.startswith("E:") and not HARMLESS_E.match(line):
            other.append(line)
    if other:
        for line in other:
            print("apt_skip_stale_index: not an index of %s: %s" % (arch, line), file=sys.stderr)
        return None
    return suites


def edit_deb822(text, suites, arch):
    """Returns (new text, number of stanzas changed)."""
    stanzas = re.split(r"\n\s*\n", text.strip("\n")) if text.strip() else []
    out, changed = [], 0
    for stanza in stanzas:
        lines = stanza.split("\n")
        fields = {}
        for line in lines:
            m = re.match(r"^([A-Za-z-]+):\s*(.*)$", line)
            if m:
                fields[m.group(1).lower()] = m.group(2).split()
        uris = [norm(u) for u in fields.get("uris", [])]
        suite_list = fields.get("suites", [])
        hit = [s for s in suite_list if any((u, s) in suites for u in uris)]
        if "deb" not in fields.get("types", []) or not hit or arch in fields.get("architectures-remove", []):
            out.append(stanza)
            continue
        rest = [s for s in suite_list if s not in hit]
        if rest:  # keep the other suites as they were, in their own stanza
            out.append("\n".join(re.sub(r"^(Suites:\s*).*$", r"\g<1>" + " ".join(rest), line, flags=re.I)
                                 for line in lines))
        new = [re.sub(r"^(Suites:\s*).*$", r"\g<1>" + " ".join(hit), line, flags=re.I) for line in lines]
        new.insert(0, "# " + MARK.format(arch=arch))
        if "architectures-remove" in fields:
            new = [line + " " + arch if re.match(r"^Architectures-Remove:", line, re.I) else line for line in new]
        else:
            new.append("Architectures-Remove: " + arch)
        out.append("\n".join(new))
        changed += 1
    return "\n\n".join(out) + "\n", changed


def edit_one_line(text, suites, arch):
    out, changed = [], 0
    for line in text.splitlines():
        m = re.match(r"^(\s*deb)(\s+\[([^\]]*)\])?\s+(\S+)\s+(\S+)(.*)$", line)
        if m and (norm(m.group(4)), m.group(5)) in suites and ("arch-=" + arch) not in (m.group(3) or ""):
            opts = ((m.group(3) or "").strip() + " arch-=" + arch).strip()
            out.append("# " + MARK.format(arch=arch))
            out.append("%s [%s] %s %s%s" % (m.group(1), opts, m.group(4), m.group(5), m.group(6)))
            changed += 1
        else:
            out.append(line)
    return "\n".join(out) + "\n", changed


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("arch")
    ap.add_argument("log")
    ap.add_argument("--etc", default="/etc/apt", help="apt's configuration folder (tests use a copy)")
    ap.add_argument("--dry-run", action="store_true")
    args = ap.parse_args()
    with open(args.log, encoding="utf-8", errors="replace") as f:
        suites = failed_suites(f.read(), args.arch)
    if not suites:
        if suites is not None:
            print("apt_skip_stale_index: no failed %s index in %s" % (args.arch, args.log), file=sys.stderr)
        return 1
    files = [os.path.join(args.etc, "sources.list")] + sorted(glob.glob(os.path.join(args.etc, "sources.list.d", "*")))
    total = 0
    for path in files:
        if not os.path.isfile(path) or not path.endswith((".list", ".sources")):
            continue
        with open(path, encoding="utf-8") as f:
            text = f.read()
        edit = edit_deb822 if path.endswith(".sources") else edit_one_line
        new, changed = edit(text, suites, args.arch)
        if changed:
            total += changed
            what = "would stop" if args.dry_run else "stopped"
            print("apt_skip_stale_index: %s fetching the %s index of %s in %s" % (
                what, args.arch, ", ".join(sorted(s for _, s in suites)), path), file=sys.stderr)
            if not args.dry_run:
                with open(path, "w", encoding="utf-8") as f:
                    f.write(new)
    if total == 0:
        print("apt_skip_stale_index: no source entry for %s" % sorted(suites), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
