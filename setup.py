"""pip install --no-build-isolation .  builds the C++ core with CMake (the repository's build/
folder, or $SDFCONTOUR_BUILD_DIR) and installs the `sdfcontour` Python package. Needs Debian's
python3-dev, pybind11-dev, python3-numpy and the C++ dependencies (scripts/setup.sh)."""
import os
import pathlib
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("SDFCONTOUR_BUILD_DIR", ROOT / "build"))
        subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                               f"-DPYTHON_EXECUTABLE={sys.executable}"])
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "_sdfcontour", "-j",
                               str(os.cpu_count() or 2)])
        built = next((build_dir / "python" / "sdfcontour").glob("_sdfcontour*.so"))
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)


setup(
    name="sdfcontour",
    version="0.1.0",
    description="Contour signed distance samples into triangle meshes (GCP, marching cubes, ...)",
    packages=["sdfcontour"],
    package_dir={"": "python"},
    ext_modules=[Extension("sdfcontour._sdfcontour", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    install_requires=["numpy"],
    python_requires=">=3.9",
)
