#!/usr/bin/env python3
"""Writes hostile recordings made from the genuine ones in tests/recordings
(a few KB of pages or index records changed or added), for the readers'
work and memory benchmark (not committed):

    python3 scripts/hostile_recordings.py OUT_DIR

then scripts/bench_hostile.sh OUT_DIR [UPETRACK] prints the table. The
integration tests (recordings/tests/hostile.rs) build the same kinds of
file in Rust; this script only makes them bigger, for timing:

- db3-shared-leaf.db3: every child of the `messages` root is its first leaf;
- db3-fanout.db3: the root's children are an interior page of 1,000 cells
  all naming a second interior page of 1,000 cells, all naming one leaf
  (8 KB added: a million leaf visits for a reader without a visited set);
- db3-dup-cells.db3: a leaf whose cell pointers all name its first cell;
- bag-dup-index.bag: the chunk-info records repeated 2,000 times;
- mcap-dup-index.mcap: the chunk indexes repeated 2,000 times.
Standard library only.
"""

import struct
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FIX = ROOT / "tests" / "recordings"


def be16(b, at):
    return struct.unpack_from(">H", b, at)[0]


def db3():
    db = bytearray((FIX / "librealsense.db3").read_bytes())
    size = be16(db, 16)
    root = 3  # the fixture's `messages` root (checked below)
    page = lambda n: slice((n - 1) * size, n * size)  # noqa: E731
    p = db[page(root)]
    assert p[0] == 0x05, "messages root is an interior page"
    cells = be16(p, 3)
    children = [struct.unpack_from(">I", p, be16(p, 12 + 2 * i))[0] for i in range(cells)]
    return db, size, root, children, page


def interior(size, child, n):
    """An interior table page of `n` cells all naming `child`, sharing one cell."""
    p = bytearray(size)
    p[0] = 0x05
    struct.pack_into(">H", p, 3, n)
    cell = size - 5
    struct.pack_into(">H", p, 5, cell)
    struct.pack_into(">I", p, 8, child)
    for i in range(n):
        struct.pack_into(">H", p, 12 + 2 * i, cell)
    struct.pack_into(">IB", p, cell, child, 1)
    return p


def point_root_at(db, root, page, target):
    p = db[page(root)]
    for i in range(be16(p, 3)):
        c = be16(p, 12 + 2 * i)
        struct.pack_into(">I", p, c, target)
    struct.pack_into(">I", p, 8, target)
    db[page(root)] = p


def main(out):
    out.mkdir(parents=True, exist_ok=True)
    db, size, root, children, page = db3()
    shared = bytearray(db)
    point_root_at(shared, root, page, children[0])
    (out / "db3-shared-leaf.db3").write_bytes(shared)

    fan = bytearray(db)
    pages = len(fan) // size
    low, high = pages + 1, pages + 2
    fan += interior(size, children[0], 1000)
    fan += interior(size, low, 1000)
    point_root_at(fan, root, page, high)
    (out / "db3-fanout.db3").write_bytes(fan)

    dup = bytearray(db)
    leaf = dup[page(children[0])]
    first = leaf[8:10]
    for i in range(1, be16(leaf, 3)):
        leaf[8 + 2 * i:10 + 2 * i] = first
    dup[page(children[0])] = leaf
    (out / "db3-dup-cells.db3").write_bytes(dup)

    bag = (FIX / "librealsense.bag").read_bytes()
    infos = bytearray()
    pos = 13
    while pos < len(bag):
        hl = struct.unpack_from("<I", bag, pos)[0]
        header = bag[pos + 4:pos + 4 + hl]
        dl = struct.unpack_from("<I", bag, pos + 4 + hl)[0]
        end = pos + 8 + hl + dl
        if b"op=\x06" in header:
            infos += bag[pos:end]
        pos = end
    (out / "bag-dup-index.bag").write_bytes(bag + bytes(infos) * 2000)

    mcap = (FIX / "ros2_png.mcap").read_bytes()
    footer = len(mcap) - 8 - 29
    pos = struct.unpack_from("<Q", mcap, footer + 9)[0]
    idx = bytearray()
    while pos < footer:
        end = pos + 9 + struct.unpack_from("<Q", mcap, pos + 1)[0]
        if mcap[pos] == 0x08:
            idx += mcap[pos:end]
        pos = end
    (out / "mcap-dup-index.mcap").write_bytes(mcap[:footer] + bytes(idx) * 2000 + mcap[footer:])
    for f in sorted(out.iterdir()):
        print(f"{f}: {f.stat().st_size} bytes")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
