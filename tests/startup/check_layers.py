#!/usr/bin/python3
"""Module layering: every "module/header.h" a target includes belongs to a target it links.

Headers are included as "module/header.h" from the one include root libcore/, so the compiler
finds any header from anywhere; only the CMake files say which modules a target may use. This
check reads them (stdlib only, no build needed) and fails on an include that the declared
dependencies do not cover.

Targets
  libcore/<module>/CMakeLists.txt  mvtm_add_library(NAME SOURCES ... PUBLIC_DEPS ... PRIVATE_DEPS ...)
  tools/<tool>/CMakeLists.txt      mvtm_add_tool(NAME SOURCES ... DEPS ...)
  A tool's DEPS are PUBLIC deps of its library mvtm_tool_NAME, and main.cpp links that library,
  so every file of the tool sees the same set. Dependencies are the mvtm::X names (each must
  name a library declared with mvtm_add_library); other names (Eigen3::Eigen, opencv_core, ...)
  are ignored. Plain add_library() targets (the dlopen'd plugin modules mvtm_oiio and mvtm_vdb,
  mvtm_glad) are outside the check, and so are their sources.

Files of a target
  Its SOURCES that exist in its folder (generated ones such as ${_embedded} are skipped), plus
  the headers of its folder that it owns (below).

Owner of a header "m/f.h" (m a folder libcore/m/ with a CMakeLists.txt declaring libraries)
  - a folder with one library: that library owns every header of the folder;
  - a folder with several libraries (libcore/workspace: workspace, projector_sources): the
    libraries whose SOURCES list f.h or a source with the stem f (f.cpp) own it; a header no
    library claims belongs to the folder's primary library, the one named after the folder
    (else the first declared).
  The rule works on names, so a generated header (base/version.h) has an owner too.

Rule (CMake's transitive PUBLIC semantics)
  A target T may include a header owned by
    T itself, or
    any library reachable from T's directly declared deps (PUBLIC_DEPS, PRIVATE_DEPS or DEPS)
    followed by PUBLIC_DEPS edges only:
      visible(T) = {T} + union over direct deps D of public_closure(D)
      public_closure(L) = {L} + union over P in PUBLIC_DEPS(L) of public_closure(P)
  A PRIVATE dep of a dep is not visible.
  A header of a library is also compiled in the library's consumers, which see only its PUBLIC
  side, so a library's header may include only headers owned by
    public_closure(T)   (T and what its PUBLIC_DEPS reach through PUBLIC_DEPS)
  and an include in a header that only T's PRIVATE_DEPS cover is reported as such (fix: move
  the dep to PUBLIC_DEPS). Every header of libcore/<module>/ counts: the include root is shared,
  so any header can be included from anywhere. (A tool's DEPS are all PUBLIC: no difference.)
  Includes without a module folder ("ptmrender.h", the tool's own folder) and of folders that
  are not libcore modules (<Eigen/Core>, "glad/gl.h") are not checked; a libcore/ folder that
  declares no library is named in a warning (stderr) and not checked. Only #include "..." lines are read; // and /* */ comments are skipped.
  Also checked: every mvtm:: dep names a declared library, and the library graph (PUBLIC and
  PRIVATE edges) has no cycle. Deps spelled mvtm_X count when X is a declared library
  (mvtm_flags, mvtm_glad are plain targets and are ignored).

Output: one line per violation
  FILE:LINE: includes "x/y.h" (module x) but TARGET does not declare mvtm::OWNER
  FILE:LINE: includes "x/y.h" (module x) in a header but TARGET reaches mvtm::OWNER only through
             PRIVATE_DEPS (a header needs it PUBLIC)
  (OWNER is the library owning the header, normally x; TARGET is the library's name or
  "tool NAME"), then exit status 1; otherwise a count of the checked includes, exit status 0.

Usage
  check_layers.py [--root SOURCE_DIR]   check the tree (default: this script's ../..)
  check_layers.py --self-test [--root]  copy libcore/ and tools/ into a temporary folder, plant
                                        undeclared includes (base including render/renderer.h,
                                        ...) and a cycle, and require the check to report
                                        exactly those among the planted lines (exit status 1)
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

HEADER_EXTS = ('.h', '.hh', '.hpp', '.inl')
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
DEP_RE = re.compile(r'^mvtm::([A-Za-z0-9_]+)$')


class Target:
    def __init__(self, kind, name, folder, cmake_file, line):
        self.kind = kind            # 'library' or 'tool'
        self.name = name
        self.folder = folder        # absolute path of the folder holding the CMakeLists.txt
        self.cmake_file = cmake_file
        self.line = line
        self.sources = []
        self.public_deps = []       # mvtm library names (without mvtm::)
        self.private_deps = []

    def label(self):
        return self.name if self.kind == 'library' else 'tool ' + self.name


# ---------------------------------------------------------------- CMake parsing

def strip_cmake_comments(text):
    """Removes # comments (and #[[ ]] bracket comments), keeping newlines and quoted strings."""
    out = []
    i, n = 0, len(text)
    in_quote = False
    while i < n:
        c = text[i]
        if in_quote:
            out.append(c)
            if c == '\\' and i + 1 < n:
                out.append(text[i + 1])
                i += 2
                continue
            if c == '"':
                in_quote = False
            i += 1
        elif c == '"':
            in_quote = True
            out.append(c)
            i += 1
        elif c == '#':
            m = re.match(r'#\[(=*)\[', text[i:])
            if m:
                end = text.find(']' + m.group(1) + ']', i)
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append('\n' * text.count('\n', i, end))
                i = end
            else:
                end = text.find('\n', i)
                i = n if end < 0 else end
        else:
            out.append(c)
            i += 1
    return ''.join(out)


def find_calls(text, command):
    """Yields (line, [arguments]) of every call of `command` (multi-line, comments stripped)."""
    text = strip_cmake_comments(text)
    for m in re.finditer(r'(?<![A-Za-z0-9_])' + command + r'\s*\(', text, re.IGNORECASE):
        depth, i = 1, m.end()
        while i < len(text) and depth:
            if text[i] == '(':
                depth += 1
            elif text[i] == ')':
                depth -= 1
            i += 1
        body = text[m.end():i - 1]
        args = [a.strip('"') for a in re.findall(r'"(?:\\.|[^"\\])*"|[^\s"]+', body)]
        yield text.count('\n', 0, m.start()) + 1, args


def split_keywords(args, keywords):
    groups = {k: [] for k in keywords}
    current = None
    for a in args[1:]:
        if a in keywords:
            current = a
        elif current:
            groups[current].append(a)
    return groups


def mvtm_names(deps, libraries=()):
    """The mvtm library names among CMake dependency names: every mvtm::X, and mvtm_X when X is
    one of `libraries` (mvtm_flags, mvtm_glad are not libraries of a module)."""
    names = []
    for d in deps:
        m = DEP_RE.match(d)
        if m:
            names.append(m.group(1))
        elif d.startswith('mvtm_') and d[len('mvtm_'):] in libraries:
            names.append(d[len('mvtm_'):])
    return names


def parse_targets(root):
    libraries, tools = [], []
    for top, command, kind in (('libcore', 'mvtm_add_library', 'library'),
                               ('tools', 'mvtm_add_tool', 'tool')):
        base = os.path.join(root, top)
        for d in sorted(os.listdir(base)):
            cmake = os.path.join(base, d, 'CMakeLists.txt')
            if not os.path.isfile(cmake):
                continue
            with open(cmake, encoding='utf-8') as f:
                text = f.read()
            for line, args in find_calls(text, command):
                if not args:
                    continue
                t = Target(kind, args[0], os.path.join(base, d), cmake, line)
                if kind == 'library':
                    g = split_keywords(args, ('SOURCES', 'PUBLIC_DEPS', 'PRIVATE_DEPS'))
                    t.public_deps = g['PUBLIC_DEPS']
                    t.private_deps = g['PRIVATE_DEPS']
                else:
                    g = split_keywords(args, ('SOURCES', 'DEPS'))
                    t.public_deps = g['DEPS']   # PUBLIC deps of mvtm_tool_NAME
                t.sources = [s for s in g['SOURCES'] if '$' not in s]
                (libraries if kind == 'library' else tools).append(t)
    return libraries, tools


# ---------------------------------------------------------------- C++ includes

def read_includes(path):
    """Yields (line number, include path) of #include "..." lines outside comments."""
    in_block = False
    with open(path, encoding='utf-8', errors='replace') as f:
        for number, raw in enumerate(f, 1):
            line, code = raw, []
            while line:
                if in_block:
                    end = line.find('*/')
                    if end < 0:
                        line = ''
                    else:
                        in_block, line = False, line[end + 2:]
                else:
                    start_block, start_line = line.find('/*'), line.find('//')
                    if start_line >= 0 and (start_block < 0 or start_line < start_block):
                        code.append(line[:start_line])
                        line = ''
                    elif start_block >= 0:
                        code.append(line[:start_block] + ' ')
                        in_block, line = True, line[start_block + 2:]
                    else:
                        code.append(line)
                        line = ''
            m = INCLUDE_RE.match(''.join(code))
            if m:
                yield number, m.group(1)


# ---------------------------------------------------------------- the check

class Layers:
    def __init__(self, root):
        self.root = root
        self.libraries, self.tools = parse_targets(root)
        self.by_name = {t.name: t for t in self.libraries}
        self.by_folder = {}                  # module folder name -> [library targets]
        for t in self.libraries:
            self.by_folder.setdefault(os.path.basename(t.folder), []).append(t)

    def deps(self, names):
        return mvtm_names(names, self.by_name)

    def owners(self, folder, filename):
        """Library names owning libcore/folder/filename (see the module docstring)."""
        targets = self.by_folder[folder]
        if len(targets) == 1:
            return [targets[0].name]
        stem = os.path.splitext(os.path.basename(filename))[0]
        claimed = [t.name for t in targets
                   if filename in t.sources
                   or stem in (os.path.splitext(os.path.basename(s))[0] for s in t.sources)]
        if claimed:
            return claimed
        primary = [t.name for t in targets if t.name == folder]
        return primary or [targets[0].name]

    def public_closure(self, name, seen=None):
        seen = set() if seen is None else seen
        if name in seen or name not in self.by_name:
            return seen
        seen.add(name)
        for p in self.deps(self.by_name[name].public_deps):
            self.public_closure(p, seen)
        return seen

    def visible(self, target):
        names = {target.name} if target.kind == 'library' else set()
        for d in self.deps(target.public_deps + target.private_deps):
            names |= self.public_closure(d)
        return names

    def files(self, target):
        """The target's existing sources plus the headers of its folder it owns."""
        files = []
        for s in target.sources:
            path = os.path.join(target.folder, s)
            if os.path.isfile(path):
                files.append(path)
        for f in sorted(os.listdir(target.folder)):
            path = os.path.join(target.folder, f)
            if not f.endswith(HEADER_EXTS) or path in files:
                continue
            if target.kind == 'tool' or target.name in self.owners(os.path.basename(target.folder), f):
                files.append(path)
        return files

    def check(self):
        problems, checked = [], 0
        rel = lambda p: os.path.relpath(p, self.root)
        # Declared deps name declared libraries.
        for t in self.libraries + self.tools:
            for d in self.deps(t.public_deps + t.private_deps):
                if d not in self.by_name:
                    problems.append('%s:%d: %s declares mvtm::%s, which no libcore CMakeLists.txt'
                                    ' defines' % (rel(t.cmake_file), t.line, t.label(), d))
        # No cycle among libraries (PUBLIC and PRIVATE edges).
        for cycle in self.cycles():
            problems.append('%s:%d: dependency cycle %s' % (
                rel(self.by_name[cycle[0]].cmake_file), self.by_name[cycle[0]].line,
                ' -> '.join('mvtm::' + c for c in cycle)))
        # Includes.
        for t in self.libraries + self.tools:
            visible = self.visible(t)
            interface = self.public_closure(t.name) if t.kind == 'library' else visible
            for path in self.files(t):
                header = path.endswith(HEADER_EXTS)
                for number, inc in read_includes(path):
                    parts = inc.split('/')
                    if len(parts) < 2 or parts[0] not in self.by_folder:
                        continue
                    checked += 1
                    owners = self.owners(parts[0], '/'.join(parts[1:]))
                    names = ' or '.join('mvtm::' + o for o in owners)
                    where = '%s:%d: includes "%s" (module %s)' % (rel(path), number, inc, parts[0])
                    if not visible.intersection(owners):
                        problems.append('%s but %s does not declare %s' % (where, t.label(), names))
                    elif header and not interface.intersection(owners):
                        problems.append('%s in a header but %s reaches %s only through PRIVATE_DEPS'
                                        ' (a header needs it PUBLIC)' % (where, t.label(), names))
        return problems, checked

    def cycles(self):
        graph = {t.name: [d for d in self.deps(t.public_deps + t.private_deps) if d in self.by_name]
                 for t in self.libraries}
        found, state, stack = [], {}, []

        def visit(n):
            state[n] = 1
            stack.append(n)
            for m in graph[n]:
                if state.get(m) == 1:
                    found.append(stack[stack.index(m):] + [m])
                elif m not in state:
                    visit(m)
            stack.pop()
            state[n] = 2

        for n in sorted(graph):
            if n not in state:
                visit(n)
        return found

    def warnings(self):
        out = []
        base = os.path.join(self.root, 'libcore')
        for d in sorted(os.listdir(base)):
            if os.path.isdir(os.path.join(base, d)) and d not in self.by_folder:
                out.append('warning: libcore/%s/ declares no library (no mvtm_add_library in a '
                           'CMakeLists.txt): its files and includes of "%s/..." are not checked' % (d, d))
        for t in self.libraries + self.tools:
            for s in t.sources:
                if not os.path.isfile(os.path.join(t.folder, s)):
                    out.append('warning: %s: source %s of %s not found' % (
                        os.path.relpath(t.cmake_file, self.root), s, t.label()))
        return out


def run_check(root):
    layers = Layers(root)
    if not layers.libraries:
        print('no mvtm_add_library found under %s/libcore' % root)
        return 1
    for w in layers.warnings():
        print(w, file=sys.stderr)
    problems, checked = layers.check()
    for p in problems:
        print(p)
    if problems:
        print('%d layering violation(s)' % len(problems))
        return 1
    print('%d module includes checked in %d libraries and %d tools: each is declared'
          % (checked, len(layers.libraries), len(layers.tools)))
    return 0


# ---------------------------------------------------------------- self-test

def append_lines(path, lines):
    """Appends lines to a file; returns the 1-based number of each appended line."""
    with open(path, encoding='utf-8') as f:
        text = f.read()
    if text and not text.endswith('\n'):
        text += '\n'
    first = text.count('\n') + 1
    with open(path, 'w', encoding='utf-8') as f:
        f.write(text + ''.join(l + '\n' for l in lines))
    return list(range(first, first + len(lines)))


def self_test(root):
    """Plants includes in a copy of libcore/ and tools/; the check must report exactly the
    undeclared ones among them (violations elsewhere in the tree are left to startup.layers)."""
    tmp = tempfile.mkdtemp(prefix='mvtm_layers_')
    try:
        for top in ('libcore', 'tools'):
            shutil.copytree(os.path.join(root, top), os.path.join(tmp, top),
                            ignore=shutil.ignore_patterns('.*', '*.o', '*.a'))
        path = lambda rel: os.path.join(tmp, rel)
        expected, planted = [], set()

        # 1. The planted undeclared include: base (no mvtm deps) includes the renderer; the same
        #    include in a // comment and in a /* */ block must not count.
        f = 'libcore/base/error.cpp'
        n = append_lines(path(f), ['// #include "render/renderer.h"', '/*',
                                   '#include "render/renderer.h"', '*/',
                                   '#include "render/renderer.h"'])
        expected.append('%s:%d: includes "render/renderer.h" (module render) but base does not '
                        'declare mvtm::render' % (f, n[4]))
        planted.add(f)

        # 2. A tool declared over several lines with comments, DEPS mvtm::mesh only:
        #    mesh's own header: fine; scene through mesh's PUBLIC_DEPS: fine; its own folder's
        #    header: fine; render, a PRIVATE dep of mesh (and only named in a comment): reported.
        os.makedirs(path('tools/zz_planted'))
        with open(path('tools/zz_planted/CMakeLists.txt'), 'w', encoding='utf-8') as out:
            out.write('# planted by check_layers.py --self-test\n'
                      'mvtm_add_tool(zz_planted  # a tool\n'
                      '  SOURCES main.cpp\n'
                      '  # DEPS mvtm::render (commented out)\n'
                      '  DEPS\n'
                      '    mvtm::mesh  # mvtm::render\n'
                      ')\n')
        open(path('tools/zz_planted/zz_planted.h'), 'w').close()
        f = 'tools/zz_planted/main.cpp'
        with open(path(f), 'w', encoding='utf-8') as out:
            out.write('#include "zz_planted.h"\n#include "mesh/corridor.h"\n'
                      '#include "scene/mesh.h"\n#include <Eigen/Core>\n'
                      '#include "render/renderer.h"\n')
        expected.append('%s:5: includes "render/renderer.h" (module render) but tool zz_planted '
                        'does not declare mvtm::render' % f)
        planted.add(f)

        # 3. A library's header including a module it has only as a PRIVATE dep (mesh: render).
        f = 'libcore/mesh/merge.h'
        n = append_lines(path(f), ['#include "render/context.h"'])
        expected.append('%s:%d: includes "render/context.h" (module render) in a header but mesh '
                        'reaches mvtm::render only through PRIVATE_DEPS (a header needs it PUBLIC)'
                        % (f, n[0]))
        planted.add(f)

        # 4. A folder with two libraries: workspace may not include projector_sources' header.
        f = 'libcore/workspace/workspace.cpp'
        n = append_lines(path(f), ['#include "workspace/workspace.h"',
                                   '#include "workspace/projector_sources.h"'])
        expected.append('%s:%d: includes "workspace/projector_sources.h" (module workspace) but '
                        'workspace does not declare mvtm::projector_sources' % (f, n[1]))
        planted.add(f)

        # 5. A dependency cycle: scene declaring mvtm::mesh (mesh declares mvtm::scene).
        f = 'libcore/scene/CMakeLists.txt'
        with open(path(f), encoding='utf-8') as cm:
            text = cm.read()
        with open(path(f), 'w', encoding='utf-8') as cm:
            cm.write(text.replace('PUBLIC_DEPS', 'PUBLIC_DEPS mvtm::mesh', 1))

        result = subprocess.run([sys.executable, os.path.abspath(__file__), '--root', tmp],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                universal_newlines=True)
        print('check on the planted copy (exit status %d):' % result.returncode)
        print(result.stdout, end='')
        out = result.stdout.splitlines()
        failures = []
        if result.returncode != 1:
            failures.append('expected exit status 1, got %d' % result.returncode)
        for e in expected:
            if e not in out:
                failures.append('missing the planted violation: ' + e)
        if not any('dependency cycle' in l and 'mvtm::scene ' in l + ' ' and 'mvtm::mesh ' in l
                   for l in out):
            failures.append('missing the planted dependency cycle mvtm::scene <-> mvtm::mesh')
        for line in out:
            if line.split(':')[0] in planted and line not in expected:
                failures.append('reported a planted include that is fine: ' + line)
        if failures:
            print('SELF-TEST FAILED')
            for f in failures:
                print('  ' + f)
            return 1
        print('self-test passed: the check fails on exactly the %d planted undeclared includes and '
              'on the planted cycle' % len(expected))
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def main():
    default_root = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                 '..', '..'))
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--root', default=default_root, help='source tree (default: %(default)s)')
    parser.add_argument('--self-test', action='store_true',
                        help='plant undeclared includes in a copy and expect the check to fail')
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    return self_test(root) if args.self_test else run_check(root)


if __name__ == '__main__':
    sys.exit(main())
