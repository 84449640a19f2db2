#!/usr/bin/env python3
"""Fails when a tool's --help options and its man page's options disagree.

usage: check_man.py TOOL_BINARY MANPAGE.1
--help: every long option on an option line (CLI11 prints "  -q,--quiet ...").
man page: every long option set in bold in the OPTIONS section (".B \\-\\-name" or
"\\fB\\-\\-name\\fR"), and the SYNOPSIS must mention each option too.
"""
import re
import subprocess
import sys

tool, man = sys.argv[1], sys.argv[2]
helptext = subprocess.run([tool, "--help"], capture_output=True, text=True, check=True).stdout
help_opts = set()
for line in helptext.splitlines():
    m = re.match(r"^\s+(-\w,)?(--[a-z0-9][a-z0-9-]*)", line)
    if m:
        help_opts.add(m.group(2))

src = open(man, encoding="utf-8").read().replace("\\-", "-")
sections = re.split(r"^\.SH\s+", src, flags=re.M)
def section(name):
    for s in sections:
        if s.upper().startswith(name) or s.upper().startswith('"' + name):
            return s
    return ""
opts_sec = section("OPTIONS")
man_opts = set(re.findall(r"(?:^\.BI?\s+|\\fB)(--[a-z0-9][a-z0-9-]*)", opts_sec, flags=re.M))
synopsis = section("SYNOPSIS")

errors = []
for o in sorted(help_opts - man_opts):
    errors.append(f"{o} is in --help but not in the OPTIONS of {man}")
for o in sorted(man_opts - help_opts):
    errors.append(f"{o} is in {man} but not in --help")
for o in sorted(help_opts - {"--help", "--version"}):
    if o not in synopsis:
        errors.append(f"{o} is missing from the SYNOPSIS of {man}")
for e in errors:
    print(e)
if not errors:
    print(f"{len(help_opts)} options agree")
sys.exit(1 if errors else 0)
