"""A result file whose global heap collection (where HDF5 keeps the string attributes)
is damaged so that its free space has size 0: HDF5 reads it in an endless loop inside
the library, which no signal or time limit can stop (the fuzz run of seed 19 hung for an
hour in ``catenet repair``). Every command that reads a result file refuses it at once
as damaged (exit 2, ``catenet.output.heaps.check_heaps``)."""

from __future__ import annotations

import struct
import subprocess
import sys

import pytest

from catenet.output.heaps import GCOL, check_heaps

CASE = """
title = "sag test"
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [10.0, 0.0, 0.0]
length = 10.2
nodes = 11
[material]
EA = 1e5
density = 1000.0
area = 1e-4
[load]
gravity = [0.0, 0.0, -9.81]
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("heap")
    (tmp / "case.toml").write_text(CASE)
    good = tmp / "good.h5"
    subprocess.run(
        [sys.executable, "-m", "catenet", "run", str(tmp / "case.toml"), "-o", str(good), "-q"],
        check=True,
    )
    data = bytearray(good.read_bytes())
    at = data.find(GCOL)
    size = struct.unpack_from("<Q", data, at + 8)[0]
    p = at + 16
    while struct.unpack_from("<H", data, p)[0] != 0:  # walk to the free space object
        p += 16 + (struct.unpack_from("<Q", data, p + 8)[0] + 7) // 8 * 8
    assert p < at + size
    struct.pack_into("<Q", data, p + 8, 0)  # its size: 0
    bad = tmp / "bad.h5"
    bad.write_bytes(bytes(data))
    return good, bad


def test_the_scan_passes_a_sound_file_and_finds_the_damage(files):
    good, bad = files
    check_heaps(good)
    with pytest.raises(OSError, match="global heap collection at byte"):
        check_heaps(bad)


@pytest.mark.parametrize(
    "command", [["repair"], ["plot", "-o", "x.png"], ["export", "--to", "vtu", "-o", "frames"]]
)
def test_every_reader_refuses_the_file_at_once(files, command, tmp_path):
    _, bad = files
    args = [sys.executable, "-m", "catenet", command[0], str(bad), *command[1:]]
    done = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "damaged" in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize("command", [["plot", "-o", "x.png"], ["report", "--format", "md"]])
def test_a_title_whose_bytes_are_not_utf8_is_drawn_with_a_replacement(files, command, tmp_path):
    """A flipped byte in the case text's title (h5py hands such bytes back as lone
    surrogates, which matplotlib's font cannot lay out): the figure and the report are
    written, the byte shown as a replacement character."""
    good, _ = files
    data = bytearray(good.read_bytes())
    at = data.find(b'title = "sag test"')
    assert at > 0
    data[at + 9] = 0xF3  # "sag test" -> "\xf3ag test": not UTF-8
    flipped = tmp_path / "flipped.h5"
    flipped.write_bytes(bytes(data))
    args = [sys.executable, "-m", "catenet", command[0], str(flipped), *command[1:]]
    done = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr
    assert done.returncode == 0, done.stderr
