"""The native extensions (``ego._native``; ``ego._fmu_guard``, the FMU watchdog): its sources need numpy's C headers, whose folder
only numpy itself knows, so the extension is declared here; everything else is in
pyproject.toml. ego falls back to the equivalent Python where the extension is not built
(``optional``). Built in place for a checkout: ``python setup.py build_ext --inplace``."""

import numpy
from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "ego._native",
            sources=["ego/_native.c"],
            include_dirs=[numpy.get_include()],
            extra_compile_args=["-O2", "-ffp-contract=off"],
            optional=True,
        ),
        # FMU calls under a watchdog (ego/fmi/guard.py): POSIX signals and threads
        Extension("ego._fmu_guard", sources=["ego/_fmu_guard.c"], extra_compile_args=["-O2"], optional=True),
    ]
)
