"""Build step that compiles the numba kernels into the package (see affordgrasp/compiled.py).

Everything else about the package is declared in pyproject.toml. After the sources are
copied to the build directory, ``python -m affordgrasp.compiled`` runs on them, so numba's
caches land next to the kernels and ship with the wheel: a fresh install's first run loads
them instead of compiling for about a minute. A failure here only costs that minute later
(the kernels then compile on first use); set AFFORDGRASP_NO_PRECOMPILE=1 to skip the step.
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
        env = dict(os.environ, PYTHONPATH=os.path.abspath(self.build_lib))
        env.pop("NUMBA_CACHE_DIR", None)  # caches next to the sources, inside the wheel
        print("compiling the affordgrasp kernels (about a minute, once per build)")
        result = subprocess.run([sys.executable, "-m", "affordgrasp.compiled"], env=env)
        if result.returncode != 0:
            print("warning: kernels not precompiled; they will compile on first use")


setup(cmdclass={"build_py": BuildPyWithKernels})
