#!/usr/bin/env python3
"""Compares the outputs of one identity case: OLD_DIR against NEW_DIR, file by file.

Used by bench/identity/run.sh. Prints one verdict on stdout, "same" or
"DIFFERENT (what)", writes every difference found to DETAILS, and exits 0 when
the two trees are the same, 1 when they differ.

Two runs of one binary differ only in what the clock and the allocator decide,
so that is all this ignores:
  * JSON: keys that hold times or memory use (seconds, seconds_*, *_per_second,
    run's speedup figures, which come from its timings, peak/held memory,
    dates); everything else, the command line included, must
    match (run.sh runs both binaries under one path, in one directory).
  * EXR: the values of header attributes that hold dates or seconds (capDate,
    DateTime, *seconds*); the rest of the file must match byte for byte. A file
    that still differs is read with idiff to say whether its pixels or only its
    header differ.
  * HTML (the report): the numbers of the timing rows ("... (s)").
Any other file must match byte for byte.
"""
import json
import os
import re
import struct
import subprocess
import sys

VOLATILE_JSON_KEY = re.compile(r"seconds|per_second|^wall$|speedup|peak_memory|memory_held|date", re.IGNORECASE)
VOLATILE_EXR_ATTRIBUTE = re.compile(r"^capDate$|^DateTime$|seconds", re.IGNORECASE)
REPORT_TIMING = re.compile(rb"(\(s\)</th><td>)[^<]*")


def without_volatile_keys(value):
    if isinstance(value, dict):
        return {k: without_volatile_keys(v) for k, v in value.items() if not VOLATILE_JSON_KEY.search(k)}
    if isinstance(value, list):
        return [without_volatile_keys(v) for v in value]
    return value


def shown(value, other):
    """A short form of a JSON value; for two long strings, from near where they part."""
    text, other_text = json.dumps(value), json.dumps(other)
    start = 0
    if isinstance(value, str) and isinstance(other, str):
        start = next((i for i, (a, b) in enumerate(zip(text, other_text)) if a != b), len(text))
        start = max(0, start - 20)
    return ("..." if start else "") + text[start:start + 60]


def json_differences(old, new, path="", found=None):
    """Paths (a.b[3].c) where two JSON values differ, the first few."""
    found = [] if found is None else found
    if len(found) >= 5:
        return found
    if isinstance(old, dict) and isinstance(new, dict):
        for key in sorted(set(old) | set(new)):
            if key not in old or key not in new:
                found.append(f"{path}.{key} only in {'new' if key in new else 'old'}")
            else:
                json_differences(old[key], new[key], f"{path}.{key}", found)
    elif isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        for index, (a, b) in enumerate(zip(old, new)):
            json_differences(a, b, f"{path}[{index}]", found)
    elif old != new:
        found.append(f"{path or '.'}: {shown(old, new)} -> {shown(new, old)}")
    return found


def exr_headers(data):
    """The attributes of every part's header: [(name, type, value offset, value size)] per part.
    Returns None when the bytes are not an EXR file this parser understands."""
    if len(data) < 8 or struct.unpack_from("<I", data, 0)[0] != 20000630:
        return None
    multipart = struct.unpack_from("<I", data, 4)[0] & 0x1000
    position, parts = 8, []
    try:
        while True:
            attributes = []
            while data[position] != 0:
                name_end = data.index(b"\0", position)
                type_end = data.index(b"\0", name_end + 1)
                (size,) = struct.unpack_from("<i", data, type_end + 1)
                attributes.append((data[position:name_end].decode("latin-1"),
                                   data[name_end + 1:type_end].decode("latin-1"), type_end + 5, size))
                position = type_end + 5 + size
            position += 1
            parts.append(attributes)
            if not multipart or data[position] == 0:
                return parts
    except (IndexError, ValueError, struct.error):
        return None


def exr_without_volatile_values(data, parts):
    blanked = bytearray(data)
    for attributes in parts:
        for name, _, offset, size in attributes:
            if VOLATILE_EXR_ATTRIBUTE.search(name):
                blanked[offset:offset + size] = bytes(size)
    return bytes(blanked)


def attribute_values(data, parts):
    """{(part, name): (type, value bytes)} of the attributes that are not volatile."""
    return {(index, name): (kind, data[offset:offset + size]) for index, attributes in enumerate(parts)
            for name, kind, offset, size in attributes if not VOLATILE_EXR_ATTRIBUTE.search(name)}


def exr_difference(old_path, new_path, old, new):
    old_parts, new_parts = exr_headers(old), exr_headers(new)
    if old_parts is None or new_parts is None:
        return "bytes", "not an EXR file this script parses"
    if exr_without_volatile_values(old, old_parts) == exr_without_volatile_values(new, new_parts):
        return None
    idiff = subprocess.run(["idiff", "-q", "-a", "-fail", "0", "-warn", "0", old_path, new_path],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if idiff.returncode != 0:
        return "EXR pixels", f"idiff exit {idiff.returncode}"
    old_attributes, new_attributes = attribute_values(old, old_parts), attribute_values(new, new_parts)
    changed = sorted({key[1] for key in set(old_attributes) | set(new_attributes)
                      if old_attributes.get(key) != new_attributes.get(key)})
    if changed:
        return "EXR header only", ", ".join(changed)
    return "EXR bytes only", "same pixels and attributes: compression or layout"


def file_difference(old_path, new_path):
    """None when the two files count as the same, else (kind, what differs)."""
    with open(old_path, "rb") as file:
        old = file.read()
    with open(new_path, "rb") as file:
        new = file.read()
    if old == new:
        return None
    name = old_path.lower()
    if name.endswith(".json"):
        try:
            old_json, new_json = json.loads(old), json.loads(new)
        except ValueError:
            return "bytes", "not JSON"
        old_json, new_json = without_volatile_keys(old_json), without_volatile_keys(new_json)
        if old_json == new_json:
            return None
        return "JSON", "; ".join(json_differences(old_json, new_json))
    if name.endswith(".exr"):
        return exr_difference(old_path, new_path, old, new)
    if name.endswith(".html"):
        if REPORT_TIMING.sub(rb"\1", old) == REPORT_TIMING.sub(rb"\1", new):
            return None
        return "HTML", "differs beyond its timing rows"
    if name.endswith(".txt") or name.endswith(".csv"):
        old_lines, new_lines = old.decode(errors="replace").splitlines(), new.decode(errors="replace").splitlines()
        for number, (a, b) in enumerate(zip(old_lines, new_lines), 1):
            if a != b:
                return "text", f"line {number}: {a[:70]!r} -> {b[:70]!r}"
        return "text", f"{len(old_lines)} lines -> {len(new_lines)} lines"
    return "bytes", "differ"


def files_under(root):
    found = set()
    for directory, _, names in os.walk(root):
        for name in names:
            found.add(os.path.relpath(os.path.join(directory, name), root))
    return found


def main():
    old_root, new_root, details_path = sys.argv[1:4]
    old_files, new_files = files_under(old_root), files_under(new_root)
    problems = [(name, "missing", "only OLD wrote it") for name in sorted(old_files - new_files)]
    problems += [(name, "missing", "only NEW wrote it") for name in sorted(new_files - old_files)]
    only_timings = 0
    for name in sorted(old_files & new_files):
        old_path, new_path = os.path.join(old_root, name), os.path.join(new_root, name)
        difference = file_difference(old_path, new_path)
        if difference:
            problems.append((name, *difference))
        elif os.path.getsize(old_path) != os.path.getsize(new_path) or \
                open(old_path, "rb").read() != open(new_path, "rb").read():
            only_timings += 1
    with open(details_path, "w") as details:
        for name, kind, what in problems:
            details.write(f"{name}: {kind}: {what}\n")
    if not problems:
        print(f"same ({len(old_files)} files" + (f"; {only_timings} equal once timings are ignored)" if only_timings else ")"))
        return 0
    # One part per kind of difference, most telling first, with its first file.
    order = ["missing", "EXR pixels", "EXR header only", "EXR bytes only", "JSON", "HTML", "text", "bytes"]
    parts = []
    for kind in order:
        files = [(name, what) for name, problem_kind, what in problems if problem_kind == kind]
        if files:
            name, what = files[0]
            count = f"{len(files)} files, e.g. " if len(files) > 1 else ""
            parts.append(f"{kind}: {count}{name} ({what[:150]})")
    print(f"DIFFERENT ({'; '.join(parts)})")
    return 1


if __name__ == "__main__":
    sys.exit(main())
