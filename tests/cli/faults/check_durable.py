#!/usr/bin/env python3
"""Reads an strace log (strace -f -y -e trace=openat,fsync,fdatasync,rename,renameat,renameat2,
unlink,unlinkat,mkdir,mkdirat) of an mvtm run and checks, from the system calls the kernel saw,
that every output reached the disk in an order a power loss cannot break:

  - a temporary renamed over a final name had its data synced (fdatasync or fsync of the file,
    after it was last opened for writing) before the rename; a folder renamed into place was
    synced itself before the rename, and every file written in it before that rename;
  - the folder of every rename, and the parent of every folder made, is synced (fsync of the
    folder) after it, before the process ends;
  - a commit journal (.mvtm-journal-*) is on the disk (its folder synced after it was renamed
    into place) before the first file of its set is renamed or removed, and the folder is synced
    after the set's last rename, before the journal is removed.

Prints one line per broken rule ("unsynced ...") and a summary line; exit 1 when a rule broke.
Usage: check_durable.py TRACE CWD
"""
import os
import re
import sys

LINE = re.compile(r'^(\d+)\s+(\w+)\((.*)\)\s+=\s+(-?\d+)')
FD = re.compile(r'^(-?\d+|AT_FDCWD)<([^>]*)>')


def strings(args):
    return re.findall(r'"((?:[^"\\]|\\.)*)"', args)


def resolve(cwd, dirfd_path, p):
    if os.path.isabs(p):
        return os.path.normpath(p)
    return os.path.normpath(os.path.join(dirfd_path or cwd, p))


def calls(trace):
    """The trace's lines, a call another thread interrupted ("<unfinished ...>", then
    "<... CALL resumed>") joined into one line, placed where it returned."""
    started = {}
    for line in open(trace, errors='replace'):
        line = line.rstrip('\n')
        pid = line.split(' ', 1)[0]
        if line.endswith('<unfinished ...>'):
            started[pid] = line[:-len('<unfinished ...>')].rstrip()
            continue
        m = re.match(r'^(\d+)\s+<\.\.\. \w+ resumed>\s?(.*)$', line)
        if m:
            line = started.pop(pid, pid + ' ?(') + m.group(2)
        yield line


def events(trace, cwd):
    """(index, call, paths...) for the calls that matter, paths absolute."""
    out = []
    for line in calls(trace):
        m = LINE.match(line)
        if not m or int(m.group(4)) < 0:
            continue
        call, args = m.group(2), m.group(3)
        if call in ('fsync', 'fdatasync'):
            f = FD.match(args)
            if f:
                out.append((call, os.path.normpath(f.group(2))))
            continue
        base = cwd
        f = FD.match(args)
        if f:  # the *at calls' first argument: the folder relative names are in
            base = f.group(2) or cwd
        s = strings(args)
        if call in ('rename', 'renameat', 'renameat2') and len(s) == 2:
            if call == 'renameat2' or call == 'renameat':
                fds = re.findall(r'(?:AT_FDCWD|\d+)<([^>]*)>', args)
                a = resolve(cwd, fds[0] if fds else None, s[0])
                b = resolve(cwd, fds[1] if len(fds) > 1 else (fds[0] if fds else None), s[1])
            else:
                a, b = resolve(cwd, None, s[0]), resolve(cwd, None, s[1])
            out.append(('rename', a, b))
        elif call in ('unlink', 'unlinkat') and s:
            out.append(('unlink', resolve(cwd, base if call == 'unlinkat' else None, s[0])))
        elif call in ('mkdir', 'mkdirat') and s:
            out.append(('mkdir', resolve(cwd, base if call == 'mkdirat' else None, s[0])))
        elif call == 'openat' and s and ('O_WRONLY' in args or 'O_RDWR' in args):
            out.append(('write_open', resolve(cwd, base, s[0])))
    return out


def check(ev):
    bad = []
    synced_dir_after = {}  # index -> set of folders synced at or after it (computed lazily)
    dir_syncs = [(i, e[1]) for i, e in enumerate(ev) if e[0] == 'fsync']

    def folder_synced_between(d, lo, hi):
        return any(lo < i < hi and p == d for i, p in dir_syncs)

    def file_synced_between(f, lo, hi):
        return any(lo < i < hi and e[0] in ('fsync', 'fdatasync') and e[1] == f
                   for i, e in enumerate(ev))

    end = len(ev)
    for i, e in enumerate(ev):
        if e[0] == 'rename':
            a, b = e[1], e[2]
            if '.tmp-' not in os.path.basename(a) and '.partial' not in os.path.basename(a):
                continue  # a journal claimed by a finisher, say: not an output
            opened = max([k for k in range(i) if ev[k][0] in ('write_open', 'mkdir')
                          and ev[k][1] == a] or [-1])
            if not file_synced_between(a, opened, i):
                bad.append('unsynced data before rename: %s -> %s' % (a, b))
            if not folder_synced_between(os.path.dirname(b), i, end):
                bad.append('unsynced folder after rename: %s' % b)
        elif e[0] == 'mkdir':
            if not folder_synced_between(os.path.dirname(e[1]), i, end):
                bad.append('unsynced folder after mkdir: %s' % e[1])
        elif e[0] == 'write_open':
            # A file written in a folder that is renamed into place later (roadsplit's road),
            # not renamed itself: synced before that folder's rename.
            f = e[1]
            k = next((k for k in range(i + 1, end) if ev[k][0] == 'rename'
                      and (ev[k][1] == f or f.startswith(ev[k][1] + '/'))), None)
            if k is not None and ev[k][1] != f and not file_synced_between(f, i, k):
                bad.append('unsynced data before its folder\'s rename: %s' % f)
    # Journals: from the rename that puts one in place to its removal.
    for i, e in enumerate(ev):
        if e[0] != 'rename' or not os.path.basename(e[2]).startswith('.mvtm-journal-'):
            continue
        if os.path.basename(e[1]).startswith('.mvtm-journal-'):
            continue  # a finisher claiming a dead writer's journal: on the disk already
        journal, d = e[2], os.path.dirname(e[2])
        gone = next((k for k in range(i + 1, end) if ev[k][0] == 'unlink'
                     and ev[k][1] == journal), end)
        steps = [k for k in range(i + 1, gone) if os.path.dirname(ev[k][-1]) == d
                 and ev[k][0] in ('rename', 'unlink')]
        if not steps:
            continue
        if not folder_synced_between(d, i, steps[0]):
            bad.append('journal not on the disk before its set: %s' % journal)
        if gone < end and not folder_synced_between(d, steps[-1], gone):
            bad.append('journal removed before its set is on the disk: %s' % journal)
    return bad


def main():
    trace, cwd = sys.argv[1], os.path.abspath(sys.argv[2])
    ev = events(trace, cwd)
    bad = check(ev)
    for b in bad:
        print(b.replace(cwd + '/', ''))
    renames = sum(1 for e in ev if e[0] == 'rename')
    journals = sum(1 for e in ev if e[0] == 'rename'
                   and os.path.basename(e[2]).startswith('.mvtm-journal-'))
    print('%s: %s' % (os.path.basename(trace), 'durable' if not bad else '%d broken' % len(bad)),
          'renames' if renames > 0 else 'no rename', 'journals' if journals else 'no journal')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
