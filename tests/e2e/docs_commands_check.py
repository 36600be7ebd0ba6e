#!/usr/bin/env python3
"""The commands the docs tell a user to type must still parse.

Every command line in a fenced block of README.md and docs/*.md that starts with one of the
project's programs (harmoloc, harmoloc-train, ...), and every such command quoted in the text
(`harmoloc-train --areas ...`), is checked against that program's own
--help: each option the docs use must be one the program lists. A renamed or removed flag
then fails here instead of in a robot owner's terminal. Programs this build does not have (a
Linux board's, a cross build's) are skipped, and said so.

    docs_commands_check.py BIN_DIR SOURCE_DIR
"""
import glob
import os
import re
import subprocess
import sys

PROGRAM = re.compile(r"^\s*(?:sudo\s+)?(?:[\w./-]*/)?(harmoloc(?:-[a-z]+)?)(?=\s|$)(.*)$")
OPTION = re.compile(r"(?:^|\s)(--[a-z][a-z0-9-]*|-[a-zA-Z])(?==|\s|$)")


def commands(path):
    """(line number, program, arguments) of every command in the file's fenced blocks."""
    fence = None
    pending = ""
    start = 0
    with open(path, encoding="utf-8") as f:
        for number, raw in enumerate(f, 1):
            line = raw.rstrip("\n")
            stripped = line.strip()
            if stripped.startswith("```"):
                fence = None if fence else stripped
                pending = ""
                continue
            if not fence:
                # Commands quoted in the text: `harmoloc-train --areas FILE ...`.
                for span in re.findall(r"`(harmoloc(?:-[a-z]+)? [^`]*)`", line):
                    m = PROGRAM.match(span)
                    if m:
                        yield number, m.group(1), m.group(2)
                continue
            if pending:
                line = pending + " " + stripped
            else:
                start = number
            if line.endswith("\\"):
                pending = line[:-1]
                continue
            pending = ""
            line = line.split(" #")[0]  # a trailing comment is not part of the command
            m = PROGRAM.match(line)
            if m:
                yield start, m.group(1), m.group(2)


def help_options(binary):
    out = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise SystemExit(f"{binary} --help failed with exit status {out.returncode}")
    return set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*|-[a-zA-Z])(?=[\s,=]|$)", out.stdout))


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    bin_dir, source = sys.argv[1:]
    files = [os.path.join(source, "README.md")] + sorted(glob.glob(os.path.join(source, "docs", "*.md")))
    known = {}
    checked = failed = 0
    skipped = set()
    for path in files:
        rel = os.path.relpath(path, source)
        for number, program, args in commands(path):
            binary = os.path.join(bin_dir, program)
            if not os.path.exists(binary):
                skipped.add(program)
                continue
            if program not in known:
                known[program] = help_options(binary)
            for option in OPTION.findall(" " + args):
                checked += 1
                if option not in known[program]:
                    failed += 1
                    print(f"FAIL {rel}:{number}: {program} has no option {option} "
                          f"(its --help lists {len(known[program])})")
    print(f"{checked} options in the docs' commands checked against --help of "
          f"{len(known)} programs; {failed} unknown"
          + (f"; not in this build: {', '.join(sorted(skipped))}" if skipped else ""))
    if checked == 0:
        print("FAIL no command found: the check itself is broken")
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
