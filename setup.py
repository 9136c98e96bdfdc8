"""Build step that compiles the numba kernels into the package (affordgrasp/kernels.py).

Everything else about the package is declared in pyproject.toml. After the sources are
copied to the build directory, ``python -m affordgrasp.kernels`` runs on them, so
numba's caches land next to the kernels and ship with the wheel: a fresh install's first run
loads them instead of compiling for minutes. The build directory is put in front of the
interpreter's path, not in place of it: under pip's build isolation the build requirements
(numpy, numba...) are only reachable through the ``PYTHONPATH`` pip sets.

A failed precompile fails the build (a wheel without its kernels would silently cost every
user minutes on the first run); set ``AFFORDGRASP_NO_PRECOMPILE=1`` to build without the
caches on purpose (the kernels then compile on first use). An editable install never
precompiles: its kernels compile once on first use, with a progress line.
"""

import os
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False) or os.environ.get("AFFORDGRASP_NO_PRECOMPILE"):
            return
        build_lib = os.path.abspath(self.build_lib)
        inherited = os.environ.get("PYTHONPATH", "")
        path = build_lib + (os.pathsep + inherited if inherited else "")
        env = dict(os.environ, PYTHONPATH=path)
        env.pop("NUMBA_CACHE_DIR", None)  # caches next to the sources, inside the wheel
        env.pop("NUMBA_DISABLE_JIT", None)
        print("compiling the affordgrasp kernels into the package (a few minutes, once per build)")
        result = subprocess.run([sys.executable, "-m", "affordgrasp.kernels"], env=env)
        if result.returncode != 0:
            raise SystemExit(
                f"error: precompiling the affordgrasp kernels failed (exit {result.returncode}, "
                "see above); a package without them compiles for minutes on first use. Fix the "
                "error, or set AFFORDGRASP_NO_PRECOMPILE=1 to build without precompiled kernels."
            )


setup(cmdclass={"build_py": BuildPyWithKernels})
