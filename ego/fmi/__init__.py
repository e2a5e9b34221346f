"""FMI co-simulation: FMUs as ego controllers (and plants), ego's models exported as FMUs.

* :mod:`ego.fmi.model` - reading and checking an FMU (before anything runs);
* :mod:`ego.fmi.units` and :mod:`ego.fmi.mapping` - connecting its variables to a task;
* :mod:`ego.fmi.cosim` - one co-simulation instance (FMI 2.0 or 3.0) through its C functions;
* :mod:`ego.fmi.controller` - an FMU as a controller (``-c path/to/controller.fmu``);
* :mod:`ego.fmi.build` - building FMUs from C sources.

fmpy is imported only when an FMU is used (``pip install 'ego[fmi]'``). See docs/fmi.md.
"""
