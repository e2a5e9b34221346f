"""One co-simulation FMU instance, FMI 2.0 or 3.0, stepped through its C functions.

:class:`CoSim` extracts the FMU into a temporary folder, instantiates it, sets start values
and parameters in initialisation mode, steps it (set inputs at t, ``doStep(t, h)``, read the
outputs at t + h) and terminates and frees it (the folder removed) in :meth:`close`, which
also runs when the object is collected or the process exits. The hot path calls the FMU's
functions through ctypes with preallocated buffers: no per-step allocation beyond Python's
floats.

The FMU's log messages go to ``on_log(level, category, message)``; a status of error or
fatal (or discard) raises :class:`FmuError` carrying the FMU's own last message.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import struct
import tempfile
import weakref
from collections.abc import Callable, Sequence

from ego.control.base import ControllerError
from ego.fmi.model import FmuInfo

STATUS = {0: "OK", 1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}
LEVEL = {0: "INFO", 1: "WARN", 2: "WARN", 3: "ERROR", 4: "ERROR"}


class FmuError(ControllerError):
    """The FMU returned error/fatal, or an output that is not finite: the run ends in ``error``."""


def _cleanup(state: dict) -> None:
    """Terminate, free and remove: safe to call twice, from close() or the finalizer."""
    fmu = state.pop("fmu", None)
    if fmu is not None:
        comp = state.pop("component", None)
        try:
            if comp:
                if state.pop("initialized", False):
                    fmu.terminate_raw(comp)
                fmu.free_raw(comp)
        finally:
            try:
                fmu.freeLibrary()
            except Exception:  # noqa: BLE001 - unloading is best effort
                pass
    folder = state.pop("folder", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)


class CoSim:
    """A co-simulation instance of ``info``'s FMU."""

    def __init__(
        self,
        info: FmuInfo,
        inputs: Sequence[int],
        outputs: Sequence[int],
        on_log: Callable[[str, str, str], None] | None = None,
        instance_name: str = "ego",
    ) -> None:
        self.info = info
        self.v3 = info.fmi_version.startswith("3")
        self.on_log = on_log
        self.instance_name = instance_name
        self.last_message = ""
        self._state: dict = {}
        self._finalizer = weakref.finalize(self, _cleanup, self._state)
        n_in, n_out = len(inputs), len(outputs)
        vr_t = ctypes.c_uint32 if self.v3 else ctypes.c_uint
        self.in_vr = (vr_t * max(n_in, 1))(*inputs)
        self.in_val = (ctypes.c_double * max(n_in, 1))()
        self.out_vr = (vr_t * max(n_out, 1))(*outputs)
        self.out_val = (ctypes.c_double * max(n_out, 1))()
        self.n_in, self.n_out = n_in, n_out
        self._n_in, self._n_out = ctypes.c_size_t(n_in), ctypes.c_size_t(n_out)
        self._t, self._h = ctypes.c_double(), ctypes.c_double()
        self._pack = struct.Struct(f"{max(n_in, 1)}d").pack_into if n_in else None
        self._unpack = struct.Struct(f"{n_out}d").unpack_from if n_out else (lambda buf: ())
        self.component = None
        # doStep's out-arguments (FMI 3.0), made once
        self._flags = (ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool(), ctypes.c_double())
        self._flag_refs = tuple(ctypes.byref(f) for f in self._flags)

    # -- life cycle -----------------------------------------------------------------------------
    def _load(self) -> None:
        from fmpy import extract

        st = self._state
        folder = tempfile.mkdtemp(prefix="ego-fmu-")
        st["folder"] = folder
        extract(self.info.path, unzipdir=folder)
        kw = dict(
            guid=self.info.guid,
            unzipDirectory=folder,
            modelIdentifier=self.info.model_identifier,
            instanceName=self.instance_name,
        )
        if self.v3:
            from fmpy.fmi3 import FMU3Slave

            fmu = FMU3Slave(**kw)
        else:
            from fmpy.fmi2 import FMU2Slave

            fmu = FMU2Slave(**kw)
        dll = fmu.dll
        # the hot path's functions without ctypes argtypes (fmpy's copies have them): every
        # argument is passed ready-made (c_void_p, c_size_t, c_double, arrays), which halves
        # the cost of a call
        raw = dll._FuncPtr
        prefix = "fmi3" if self.v3 else "fmi2"
        self._set = raw((f"{prefix}SetFloat64" if self.v3 else "fmi2SetReal", dll))
        self._get = raw((f"{prefix}GetFloat64" if self.v3 else "fmi2GetReal", dll))
        self._do_step = raw((f"{prefix}DoStep", dll))
        fmu.terminate_raw = getattr(dll, f"{prefix}Terminate")
        fmu.free_raw = getattr(dll, f"{prefix}FreeInstance")
        st["fmu"] = fmu
        self.fmu = fmu

    def _log(self, status: int, category: str, message: str) -> None:
        if status >= 1:  # the message an error or non-finite output is reported with
            self.last_message = message
        if self.on_log is not None:
            self.on_log(LEVEL.get(status, "INFO"), category, message)

    def _instantiate(self) -> None:
        fmu = self.fmu
        if self.v3:
            from fmpy.fmi3 import fmi3IntermediateUpdateCallback, fmi3LogMessageCallback

            def log(env, status, category, message):
                self._log(
                    int(status),
                    (category or b"").decode("utf-8", "replace"),
                    (message or b"").decode("utf-8", "replace"),
                )

            self._log_cb = fmi3LogMessageCallback(log)
            comp = fmu.dll.fmi3InstantiateCoSimulation(
                self.instance_name.encode(),
                self.info.guid.encode(),
                (os.path.join(fmu.unzipDirectory, "resources") + os.sep).encode(),
                False,
                True,
                False,
                False,
                None,
                0,
                None,
                self._log_cb,
                fmi3IntermediateUpdateCallback(),
            )
        else:
            from fmpy import calloc, free
            from fmpy.fmi2 import (
                fmi2CallbackAllocateMemoryTYPE,
                fmi2CallbackFreeMemoryTYPE,
                fmi2CallbackFunctions,
                fmi2CallbackLoggerTYPE,
                fmi2CoSimulation,
            )

            def log(env, name, status, category, message):
                self._log(
                    int(status),
                    (category or b"").decode("utf-8", "replace"),
                    (message or b"").decode("utf-8", "replace"),
                )

            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(log)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, size: calloc(n, size))
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: free(p))
            self._callbacks = cb
            import pathlib

            comp = fmu.dll.fmi2Instantiate(
                self.instance_name.encode(),
                fmi2CoSimulation,
                self.info.guid.encode(),
                pathlib.Path(fmu.unzipDirectory, "resources").as_uri().encode(),
                ctypes.byref(cb),
                0,
                1,
            )
        if not comp:
            raise FmuError(
                f"FMU {self.info.model_name}: instantiation failed"
                + (f": {self.last_message}" if self.last_message else "")
            )
        self.component = comp
        self._comp = ctypes.c_void_p(comp)
        self._state["component"] = comp

    def start(self, parameters: dict[int, float], start_time: float = 0.0) -> None:
        """(Re)start at ``start_time``: reset the live instance (fmi2Reset/fmi3Reset) or
        instantiate one, set ``parameters`` (value reference -> value), run initialisation."""
        st = self._state
        if "fmu" not in st:
            self._load()
        dll = self.fmu.dll
        if self.component is not None:
            if st.pop("initialized", False):
                self._check((dll.fmi3Terminate if self.v3 else dll.fmi2Terminate)(self.component), "terminate")
            self._check((dll.fmi3Reset if self.v3 else dll.fmi2Reset)(self.component), "reset")
        else:
            self._instantiate()
        comp = self.component
        if parameters:
            vrs = list(parameters)
            vr_t = ctypes.c_uint32 if self.v3 else ctypes.c_uint
            arr_vr = (vr_t * len(vrs))(*vrs)
            arr_val = (ctypes.c_double * len(vrs))(*(parameters[v] for v in vrs))
        if self.v3:
            if parameters:
                self._check(dll.fmi3SetFloat64(comp, arr_vr, len(vrs), arr_val, len(vrs)), "set parameters")
            self._check(
                dll.fmi3EnterInitializationMode(comp, False, 0.0, start_time, False, 0.0), "enter initialisation mode"
            )
            st["initialized"] = True
            self._check(dll.fmi3ExitInitializationMode(comp), "exit initialisation mode")
        else:
            self._check(dll.fmi2SetupExperiment(comp, 0, 0.0, start_time, 0, 0.0), "setup experiment")
            if parameters:
                self._check(dll.fmi2SetReal(comp, arr_vr, len(vrs), arr_val), "set parameters")
            self._check(dll.fmi2EnterInitializationMode(comp), "enter initialisation mode")
            st["initialized"] = True
            self._check(dll.fmi2ExitInitializationMode(comp), "exit initialisation mode")

    def _check(self, status: int, what: str) -> None:
        if status > 1:
            msg = self.last_message or f"status {STATUS.get(status, status)}"
            raise FmuError(f"FMU {self.info.model_name} ({what}): {STATUS.get(status, status)}: {msg}")

    def exchange(self, values, t: float, h: float) -> tuple[float, ...]:
        """Inputs ``values`` (in value-reference order of ``inputs``) in at t, one
        communication step to t + h, the outputs out (a tuple)."""
        if self.n_in:
            self._pack(self.in_val, 0, *values)
        self._t.value = t
        self._h.value = h
        comp, n_in, n_out = self._comp, self._n_in, self._n_out
        if self.v3:
            if self.n_in:
                status = self._set(comp, self.in_vr, n_in, self.in_val, n_in)
                if status > 1:
                    self._check(status, f"set inputs at t = {t:.3f} s")
            status = self._do_step(comp, self._t, self._h, 1, *self._flag_refs)
            if status > 1:
                self._check(status, f"doStep at t = {t:.3f} s")
            if self.n_out:
                status = self._get(comp, self.out_vr, n_out, self.out_val, n_out)
        else:
            if self.n_in:
                status = self._set(comp, self.in_vr, n_in, self.in_val)
                if status > 1:
                    self._check(status, f"set inputs at t = {t:.3f} s")
            status = self._do_step(comp, self._t, self._h, 1)
            if status > 1:
                self._check(status, f"doStep at t = {t:.3f} s")
            if self.n_out:
                status = self._get(comp, self.out_vr, n_out, self.out_val)
        if self.n_out and status > 1:
            self._check(status, f"get outputs at t = {t + h:.3f} s")
        return self._unpack(self.out_val)

    def get(self, vrs: Sequence[int]) -> list[float]:
        vr_t = ctypes.c_uint32 if self.v3 else ctypes.c_uint
        arr_vr = (vr_t * len(vrs))(*vrs)
        val = (ctypes.c_double * len(vrs))()
        n = ctypes.c_size_t(len(vrs))
        status = self._get(self._comp, arr_vr, n, val, n) if self.v3 else self._get(self._comp, arr_vr, n, val)
        self._check(status, "get")
        return list(val)

    def close(self) -> None:
        """Terminate and free the instance, unload the library, remove the extracted folder."""
        self.component = None
        self._finalizer()
