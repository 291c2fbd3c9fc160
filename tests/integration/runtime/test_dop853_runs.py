"""A joint run with method dop853 stopped by a signal keeps the rows computed (the C driver is
called once per chunk of output intervals, runtime.driver polls between chunks), as the CVODES
run does (tests/integration/test_hostile.py)."""

import json
import signal
import subprocess
import sys
import time

from tests.integration.test_hostile import ENV, LONG, casmech, limit_memory


def test_interrupt_keeps_the_rows_computed(tmp_path):
    (tmp_path / "long.yaml").write_text(LONG.replace("formulation: FORMULATION",
                                                     "formulation: joint, method: dop853"))
    code, output, _ = casmech(["run", "long.yaml", "--out", "out", "--t-end", "0.5"], tmp_path)
    assert code == 0, output
    process = subprocess.Popen([sys.executable, "-m", "casmech.cli", "run", "long.yaml",
                                "--out", "out"], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, preexec_fn=limit_memory,
                               env=ENV)
    written = tmp_path / "out/results.csv"
    waited = time.perf_counter() + 6.0
    while time.perf_counter() < waited and (not written.exists() or written.read_bytes().count(
            b"\n") <= 7):  # until more rows than the first run's 6 are on disk (or 6 s)
        time.sleep(0.1)
    assert process.poll() is None, process.communicate()[0]
    process.send_signal(signal.SIGINT)
    sent = time.perf_counter()
    output = process.communicate(timeout=30)[0]
    assert time.perf_counter() - sent < 10.0
    assert "Traceback" not in output, output
    assert process.returncode == 128 + signal.SIGINT, output
    meta = json.loads((tmp_path / "out/metadata.json").read_text())
    assert meta["status"] == "interrupted"
    from casmech.io.csv import read_csv

    names, values = read_csv(tmp_path / "out/results.csv")
    assert names[0] == "t" and len(values) == meta["rows"] > 6
    assert values[0, 0] == 0.0 and (values[1:, 0] > values[:-1, 0]).all()
