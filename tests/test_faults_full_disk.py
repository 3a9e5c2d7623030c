"""Issue 42: a REAL full disk (ENOSPC from the kernel, not a monkeypatched call), docs/reliability.md.

Without root: ``unshare -rm`` makes a user and mount namespace in which this user may mount a small
tmpfs (Linux >= 3.8 with unprivileged user namespaces). Inside it a script copies a good earlier run
of a study into the tmpfs, fills the tmpfs to 60 kB free, runs the study again (its JSON alone is
~140 kB), then copies what is left out of the namespace and runs once more with room. Skipped where
``unshare`` is missing or the kernel refuses the namespace or the mount.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.fast_study import fast_study
from tests.test_faults import _no_seconds
from tests.test_study_outputs import _run

ROOT = Path(__file__).resolve().parents[1]
FREE = 60_000                     # bytes left on the disk for the second run


def _namespaces_mount(tmp: Path) -> str | None:
    """None when ``unshare -rm`` can mount a tmpfs here, else why not."""
    if shutil.which("unshare") is None:
        return "no unshare command"
    probe = tmp / "probe"
    probe.mkdir()
    try:
        res = subprocess.run(["unshare", "-rm", "sh", "-c", f"mount -t tmpfs -o size=64k tmpfs '{probe}'"],
                             capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"unshare failed: {exc}"
    return None if res.returncode == 0 else f"unshare -rm + mount tmpfs refused: {' '.join(res.stderr.split())}"


FILL = """
import os, sys
st = os.statvfs(sys.argv[1])
with open(os.path.join(sys.argv[1], "filler"), "wb") as f:
    f.write(b"\\0" * (st.f_bavail * st.f_frsize - int(sys.argv[2])))
"""

SCRIPT = """
set -e
mount -t tmpfs -o size=16m tmpfs "$DISK"
mkdir "$DISK/out" && cp -a "$GOOD/." "$DISK/out/"
"$PY" -c "$FILL" "$DISK" "$FREE"
set +e
"$PY" -m evotol.cli -q run "$STUDY" --out "$DISK/out" 2> "$RES/err"
echo $? > "$RES/rc"
cp -a "$DISK/out/." "$RES/after/"
rm "$DISK/filler"
"$PY" -m evotol.cli -q run "$STUDY" --out "$DISK/out" > /dev/null 2> "$RES/err2"
echo $? > "$RES/rc2"
cp "$DISK/out/ucr3_example.json" "$RES/rerun.json"
"""


# Slow (~7-10 s) because its check is strong: three real study runs (a good one, one on a full tmpfs, one after).
def test_a_real_full_disk_is_one_line_and_keeps_the_earlier_files(tmp_path, capsys):
    why = _namespaces_mount(tmp_path)
    if why:
        pytest.skip(why)
    study = fast_study(tmp_path / "s")
    good, res, disk = tmp_path / "good", tmp_path / "res", tmp_path / "disk"
    assert _run(["run", str(study), "--out", str(good)], capsys)[0] == 0
    (res / "after").mkdir(parents=True)
    disk.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "DISK": str(disk), "GOOD": str(good), "RES": str(res),
           "STUDY": str(study), "PY": sys.executable, "FILL": FILL, "FREE": str(FREE)}
    proc = subprocess.run(["unshare", "-rm", "sh", "-c", SCRIPT], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    err = (res / "err").read_text(encoding="utf-8")
    assert (res / "rc").read_text().strip() == "3", err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith("evotol: error: cannot write ") and "disk full" in err and "No space left" in err, err
    failed = Path(err.split("cannot write ")[1].split(":")[0]).name
    earlier = {p.name: p.read_bytes() for p in good.iterdir()}
    after = {p.name: p.read_bytes() for p in (res / "after").iterdir() if p.name != "filler"}
    assert not [n for n in after if n.startswith(".") or n.endswith(".lock")], sorted(after)   # no temp file, no lock
    assert set(after) == set(earlier), (sorted(after), sorted(earlier))
    assert failed == "ucr3_example.json"                          # the first large file of the run
    changed = sorted(n for n in after if after[n] != earlier[n])
    assert changed == ["ucr3_example.manifest.json"], changed     # every output byte-identical to the earlier run's
    manifest = json.loads(after["ucr3_example.manifest.json"])
    assert manifest["complete"] is False and manifest["files"] == {   # it still vouches for the earlier files
        n: hashlib.sha256(b).hexdigest() for n, b in earlier.items() if n.startswith("ucr3_example") and "manifest" not in n}
    assert (res / "rc2").read_text().strip() == "0", (res / "err2").read_text()   # once the disk has room
    rerun = json.loads((res / "rerun.json").read_text(encoding="utf-8"))
    assert _no_seconds(rerun) == _no_seconds(json.loads(earlier["ucr3_example.json"]))

