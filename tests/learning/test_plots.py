"""Model plots: PNG files, drawn without switching the caller's matplotlib backend."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def test_plots_leave_the_callers_backend_and_pyplot_alone(tmp_path):
    code = textwrap.dedent(
        f"""
        import sys
        import matplotlib
        import numpy as np
        matplotlib.use("svg")
        from affordgrasp.learning.plots import plot_pr_curves, plot_scatter
        rng = np.random.default_rng(0)
        y = rng.random(50) < 0.3
        plot_pr_curves({str(tmp_path / "pr.png")!r}, {{"m": (y, rng.random(50))}}, 0.3)
        plot_scatter({str(tmp_path / "s.png")!r}, rng.random(50), rng.random(50), "m")
        assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
        assert "matplotlib.pyplot" not in sys.modules
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    for name in ("pr.png", "s.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
