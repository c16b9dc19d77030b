#!/usr/bin/env python3
"""The device kit's shared libraries: what its programs load, for a machine with none of them.

Usage: device-kit-libraries.py --into LIB [--stub SONAME]... FILE...

Copies into LIB every shared library the ELF files FILE (programs, and libraries that are
loaded with dlopen, such as Mesa's GLX vendor library and DRI driver) need, the whole
closure of their DT_NEEDED entries as this machine's loader resolves them (`ldd`), each
under its soname, and the loader itself as LIB/ld-linux-x86-64.so.2. The kit runs every
program through that loader with `--library-path LIB`, so that no library of the other
machine (another glibc among them) mixes with Debian's.

--stub SONAME puts in place of that library a stub made here: it defines, with the same
symbol versions, every symbol the kit's other libraries import from it, and any call to
one prints the library's name and aborts. It is for libraries that are linked but never
called on the kit's paths: LLVM links Z3 (for clang's static analyzer) and libxml2 (for
Windows manifests), and llvmpipe uses neither; the two and ICU's data behind libxml2 are
a third of the kit's size. Without the stubs the kit is larger than the issue's 48 MiB.

Prints one line per library copied and a summary.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile


def run(*command):
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def needed(path):
    """The DT_NEEDED sonames of an ELF file, in order."""
    return re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", run("readelf", "-d", path))


def resolved(paths):
    """soname -> path for every library `ldd` finds for `paths`; exits on one not found."""
    found, missing = {}, []
    for path in paths:
        for line in run("ldd", path).splitlines():
            parts = line.split()
            if "=>" not in parts:
                continue
            name, target = parts[0], parts[parts.index("=>") + 1]
            if target == "not":
                missing.append(f"{name} (needed by {path})")
            else:
                found.setdefault(name, target)
    if missing:
        sys.exit("device-kit-libraries: not found: " + ", ".join(missing))
    return found


def interpreter(path):
    match = re.search(r"\[Requesting program interpreter: ([^\]]+)\]", run("readelf", "-l", path))
    return match.group(1) if match else None


def closure(roots, stubs):
    """The libraries the roots need (soname -> path), walking DT_NEEDED but not into stubs;
    for each stub the files that import from it; and soname -> path of everything found."""
    where = resolved(roots)
    libraries, importers, pending = {}, {s: [] for s in stubs}, list(roots)
    seen = set()
    while pending:
        path = pending.pop()
        if path in seen:
            continue
        seen.add(path)
        for name in needed(path):
            if name.startswith("ld-linux"):
                continue
            if name in stubs:
                importers[name].append(path)
                continue
            if name not in where:
                where.update(resolved([path]))
            if name not in libraries:
                libraries[name] = where[name]
                pending.append(where[name])
    for name in stubs:
        if not importers[name]:
            sys.exit(f"device-kit-libraries: nothing the kit loads needs {name}: drop --stub {name}")
    return libraries, importers, where


def dynamic_symbols(path):
    """(name, version, kind, size, defined) of every dynamic symbol of `path` (objdump -T)."""
    symbols = []
    for line in run("objdump", "-T", path).splitlines():
        match = re.match(
            r"^[0-9a-f]+ \S*\s+(\S+)\s+(\*UND\*|\S+)\s+([0-9a-f]+)\s+(?:\(?([\w.@]+)\)?\s+)?(\S+)$",
            line)
        if not match:
            continue
        kind, section, size, version, name = match.groups()
        version = "" if version in (None, "Base") else version
        symbols.append((name, version, kind, int(size, 16), section != "*UND*"))
    return symbols


def make_stub(soname, importers, real, into):
    """Compiles a stub of `soname` defining what `importers` take from `real`."""
    defined = {(n, v): (k, s) for n, v, k, s, d in dynamic_symbols(real) if d}
    wanted = {}
    for importer in importers:
        for name, version, _, _, is_defined in dynamic_symbols(importer):
            if not is_defined and (name, version) in defined:
                wanted[(name, version)] = defined[(name, version)]
    if not wanted:
        sys.exit(f"device-kit-libraries: found no symbol imported from {soname}")
    source = [
        "/* A stub made by the device kit (scripts/device/device-kit-libraries.py). */",
        "#include <stdio.h>",
        "#include <stdlib.h>",
        "static void mtpt_kit_stub_called(const char* symbol) {",
        f'  fprintf(stderr, "mtpt device kit: %s of {soname} called, which the kit carries as a '
        'stub\\n", symbol);',
        "  abort();",
        "}",
    ]
    versions = {}
    for (name, version), (kind, size) in sorted(wanted.items()):
        if kind == "DO":
            source.append(f"char {name}[{max(size, 1)}] __attribute__((aligned(16)));")
        else:
            source.append(f'void {name}(void) {{ mtpt_kit_stub_called("{name}"); }}')
        versions.setdefault(version, []).append(name)
    # One node per version; the first hides everything else (the helper above).
    script = []
    for version, names in versions.items():
        body = " ".join(f"{n};" for n in names) + ("" if script else " local: *;")
        script.append(f"{version} {{ global: {body} }};")
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "stub.c"), "w") as f:
            f.write("\n".join(source) + "\n")
        with open(os.path.join(work, "stub.map"), "w") as f:
            f.write("\n".join(script) + "\n")
        subprocess.run(["cc", "-shared", "-fPIC", "-O1", "-o", os.path.join(into, soname),
                        f"-Wl,-soname,{soname}", f"-Wl,--version-script={work}/stub.map",
                        os.path.join(work, "stub.c")], check=True)
    return len(wanted)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--into", required=True)
    parser.add_argument("--stub", action="append", default=[])
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    os.makedirs(args.into, exist_ok=True)
    libraries, importers, where = closure(args.files, set(args.stub))
    for name, path in sorted(libraries.items()):
        shutil.copy2(os.path.realpath(path), os.path.join(args.into, name))
    loader = interpreter(args.files[0])
    if not loader:
        sys.exit(f"device-kit-libraries: {args.files[0]} names no program interpreter")
    shutil.copy2(os.path.realpath(loader), os.path.join(args.into, "ld-linux-x86-64.so.2"))
    total = sum(os.path.getsize(os.path.join(args.into, n)) for n in libraries)
    print(f"device-kit-libraries: {len(libraries)} libraries, {total / 2**20:.1f} MiB, "
          f"and the loader {loader}")
    for soname, files in sorted(importers.items()):
        count = make_stub(soname, files, where[soname], args.into)
        print(f"device-kit-libraries: {soname} is a stub of the {count} symbols "
              f"{', '.join(os.path.basename(f) for f in files)} import from {where[soname]}")


if __name__ == "__main__":
    main()
