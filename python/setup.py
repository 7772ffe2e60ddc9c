"""Builds the csgvox extension with the project's CMake build.

The build folder is the repository's `build/` (the one the README's build
command makes), or CSGVOX_BUILD_DIR; an existing build is reused, so after
`cmake --build build` only the module is compiled. The module is built for
the interpreter running pip.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent.parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = Path(os.environ.get("CSGVOX_BUILD_DIR", ROOT / "build")).resolve()
        python = os.path.realpath(sys.executable)
        subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir),
                               "-DCSGVOX_PYTHON=ON", f"-DPython3_EXECUTABLE={python}"])
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "csgvox_python",
                               "--parallel", str(os.cpu_count() or 2)])
        suffix = subprocess.check_output(
            [python, "-c", "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))"],
            text=True).strip()
        built = build_dir / "python" / ("csgvox" + suffix)
        if not built.exists():
            raise RuntimeError(f"{built}: not built")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


setup(ext_modules=[Extension("csgvox", sources=[])], cmdclass={"build_ext": CMakeBuild})
