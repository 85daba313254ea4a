"""pip install --no-build-isolation .  builds the C++ core with CMake (the repository's build/
folder, or $SDFCONTOUR_BUILD_DIR; in parallel, its progress shown with pip's -v) and installs the
`sdfcontour` Python package and the `sdfcontour` command (the C++ program, carried inside the
package with its OpenVDB module). Needs Debian's python3-dev, pybind11-dev, python3-numpy and the
C++ dependencies (scripts/setup.sh); pyproject.toml names the build's Python requirements."""
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
        if not (build_dir / "libsdfcontour.a").exists():
            cores = os.cpu_count() or 2
            print(f"sdfcontour: no build in {build_dir}: compiling the C++ core, about "
                  f"{max(2, round(30 / cores))} minutes on {cores} cores (bash scripts/build.sh "
                  f"first makes pip take seconds)", file=sys.stderr, flush=True)
        subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                               f"-DPYTHON_EXECUTABLE={sys.executable}"])
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "_sdfcontour",
                               "sdfcontour_cli", "sdfcontour_openvdb", "-j", str(os.cpu_count() or 2)])
        built = next((build_dir / "python" / "sdfcontour").glob("_sdfcontour*.so"))
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)
        # The command-line program and the OpenVDB module it loads from beside itself.
        programs = target.parent / "_bin"
        programs.mkdir(exist_ok=True)
        for name in ("sdfcontour", "sdfcontour_openvdb.so"):
            shutil.copy2(build_dir / name, programs / name)


setup(
    name="sdfcontour",
    version="0.1.0",
    description="Contour signed distance samples into triangle meshes (GCP, marching cubes, ...)",
    packages=["sdfcontour"],
    package_dir={"": "python"},
    ext_modules=[Extension("sdfcontour._sdfcontour", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    install_requires=["numpy"],
    extras_require={"dask": ["dask", "distributed", "zarr", "h5py"]},
    entry_points={"console_scripts": ["sdfcontour = sdfcontour._cli:main"]},
    python_requires=">=3.9",
)
