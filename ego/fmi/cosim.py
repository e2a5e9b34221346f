"""One co-simulation FMU instance, FMI 2.0 or 3.0, stepped through its C functions.

:class:`CoSim` extracts the FMU into a temporary folder, instantiates it, sets start values
and parameters in initialisation mode, steps it (set inputs at t, ``doStep(t, h)``, read the
outputs at t + h) and terminates and frees it (the folder removed) in :meth:`close`, which
also runs when the object is collected or the process exits. The hot path calls the FMU's
functions through ``ego._fmu_guard`` (:mod:`ego.fmi.guard`: every call under the watchdog of
the step limit, Ctrl-C/SIGTERM and crashes), one C call per communication step.

The FMU's log messages go to ``on_log(level, category, message)``; a status of error or
fatal (or discard) raises :class:`FmuError` carrying the FMU's own last message.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import weakref
from collections.abc import Callable, Sequence

from ego.control.base import ControllerError
from ego.fmi.guard import abort_error, arm, extraction_dir, native
from ego.fmi.model import FmuInfo
from ego.params import ConfigError

STATUS = {0: "OK", 1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}
LEVEL = {0: "INFO", 1: "WARN", 2: "WARN", 3: "ERROR", 4: "ERROR"}


class FmuError(ControllerError):
    """The FMU returned error/fatal, or an output that is not finite: the run ends in ``error``."""


def _cleanup(state: dict) -> None:
    """Terminate, free and remove: safe to call twice, from close() or the finalizer. An
    instance left in the middle of a call (hung, crashed: ``abandoned``) is not called again:
    its library stays loaded, its folder is removed."""
    fmu = state.pop("fmu", None)
    abandoned = state.pop("abandoned", False)
    if fmu is not None and not abandoned:
        comp = state.pop("component", None)
        fns = state.pop("fns", {})
        try:
            if comp:
                if state.pop("initialized", False):
                    native.call("p", fns["Terminate"], comp)
                native.call("v", fns["FreeInstance"], comp)
        except Exception:  # noqa: BLE001 - an FMU failing as it is freed: nothing left to do
            pass
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
        if native is None:
            raise ConfigError(
                "FMUs need ego's C extension ego._fmu_guard (the watchdog of FMU calls): "
                "build it with python setup.py build_ext --inplace"
            )
        self.info = info
        self.v3 = info.fmi_version.startswith("3")
        self.on_log = on_log
        self.instance_name = instance_name
        self.last_message = ""
        self._state: dict = {}
        self._finalizer = weakref.finalize(self, _cleanup, self._state)
        self.inputs, self.outputs = list(inputs), list(outputs)
        self.n_in, self.n_out = len(inputs), len(outputs)
        self.component = None
        self._log_buffer = native.LogBuffer()
        self._stepper = None

    # -- life cycle -----------------------------------------------------------------------------
    def _load(self) -> None:
        from ego.fmi.model import extract

        st = self._state
        folder = extraction_dir(self.info.model_name)
        st["folder"] = folder
        try:
            extract(self.info.path, folder)
        except ConfigError as exc:  # an archive that lied about its sizes
            raise FmuError(str(exc)) from None
        kw = dict(
            guid=self.info.guid,
            unzipDirectory=folder,
            modelIdentifier=self.info.model_identifier,
            instanceName=self.instance_name,
        )
        try:
            if self.v3:
                from fmpy.fmi3 import FMU3Slave

                fmu = FMU3Slave(**kw)
            else:
                from fmpy.fmi2 import FMU2Slave

                fmu = FMU2Slave(**kw)
        except Exception as exc:  # noqa: BLE001 - not a shared library, or one for another machine
            text = " ".join(str(exc).split())[:200]
            raise FmuError(f"FMU {self.info.model_name}: its binary cannot be loaded: {text}") from None
        dll = fmu.dll
        prefix = "fmi3" if self.v3 else "fmi2"
        names = (
            "InstantiateCoSimulation SetFloat64 GetFloat64 DoStep Terminate FreeInstance Reset "
            "EnterInitializationMode ExitInitializationMode"
            if self.v3
            else "Instantiate SetReal GetReal DoStep Terminate FreeInstance Reset SetupExperiment "
            "EnterInitializationMode ExitInitializationMode"
        ).split()
        fns = {}
        for n in names:
            try:
                fns[n] = ctypes.cast(getattr(dll, prefix + n), ctypes.c_void_p).value
            except AttributeError:
                fns[n] = None
        self._fns = st["fns"] = fns
        st["fmu"] = fmu
        self.fmu = fmu

    def _call(self, kind: str, fn: str, *args, what: str = "", t: float | None = None):
        """One guarded call of FMI function ``fn``; the FMU's messages then passed on."""
        address = self._fns.get(fn)
        if address is None:
            raise FmuError(f"FMU {self.info.model_name}: its binary has no {'fmi3' if self.v3 else 'fmi2'}{fn}")
        try:
            return native.call(kind, address, *args)
        except native.Aborted as exc:
            self._abandon()
            raise abort_error(
                exc.args, self.info.model_name, what or f"{'fmi3' if self.v3 else 'fmi2'}{fn}", t
            ) from None
        finally:
            if self._log_buffer.pending:
                for status, category, message in self._log_buffer.drain():
                    self._log(status, category, message)

    def _abandon(self) -> None:
        """The instance was left mid-call: never called again (close only removes its folder)."""
        self._state["abandoned"] = True
        self._stepper = None

    def _log(self, status: int, category: str, message: str) -> None:
        if status >= 1:  # the message an error or non-finite output is reported with
            self.last_message = message
        if self.on_log is not None:
            self.on_log(LEVEL.get(status, "INFO"), category, message)

    def _instantiate(self) -> None:
        fmu = self.fmu
        env, callbacks, logger = self._log_buffer.addresses()
        name, guid = self.instance_name.encode(), self.info.guid.encode()
        if self.v3:
            resources = (os.path.join(fmu.unzipDirectory, "resources") + os.sep).encode()
            args = (name, guid, resources, 0, 1, 0, 0, None, 0, env, logger, None)
            comp = self._call("inst3", "InstantiateCoSimulation", *args, what="fmi3InstantiateCoSimulation")
        else:
            import pathlib

            uri = pathlib.Path(fmu.unzipDirectory, "resources").as_uri().encode()
            comp = self._call("inst2", "Instantiate", name, 1, guid, uri, callbacks, 0, 1, what="fmi2Instantiate")
        if not comp:
            raise FmuError(
                f"FMU {self.info.model_name}: instantiation failed"
                + (f": {self.last_message}" if self.last_message else "")
            )
        self.component = comp
        self._state["component"] = comp
        self._stepper = native.Stepper(
            self.v3,
            comp,
            self._fns["SetFloat64" if self.v3 else "SetReal"] or 0,
            self._fns["GetFloat64" if self.v3 else "GetReal"] or 0,
            self._fns["DoStep"] or 0,
            self.inputs,
            self.outputs,
            self._log_buffer,
            self._log,
        )

    def start(self, parameters: dict[int, float], start_time: float = 0.0) -> None:
        """(Re)start at ``start_time``: reset the live instance (fmi2Reset/fmi3Reset) or
        instantiate one, set ``parameters`` (value reference -> value), run initialisation."""
        st = self._state
        if st.get("abandoned"):
            raise FmuError(f"FMU {self.info.model_name}: its instance was abandoned (hung or crashed)")
        arm()
        if "fmu" not in st:
            self._load()
        call = self._call
        if self.component is not None:
            if st.pop("initialized", False):
                self._check(call("p", "Terminate", self.component), "terminate")
            self._check(call("p", "Reset", self.component), "reset")
        else:
            self._instantiate()
        comp = self.component
        if parameters:
            vrs = list(parameters)
            vr_t = ctypes.c_uint32 if self.v3 else ctypes.c_uint
            arr_vr = (vr_t * len(vrs))(*vrs)
            arr_val = (ctypes.c_double * len(vrs))(*(float(parameters[v]) for v in vrs))
            addr_vr, addr_val = ctypes.addressof(arr_vr), ctypes.addressof(arr_val)
        if self.v3:
            if parameters:
                self._check(call("real3", "SetFloat64", comp, addr_vr, len(vrs), addr_val), "set parameters")
            self._check(
                call("init3", "EnterInitializationMode", comp, 0, 0.0, float(start_time), 0, 0.0),
                "enter initialisation mode",
            )
            st["initialized"] = True
            self._check(call("p", "ExitInitializationMode", comp), "exit initialisation mode")
        else:
            self._check(call("setup2", "SetupExperiment", comp, 0, 0.0, float(start_time), 0, 0.0), "setup experiment")
            if parameters:
                self._check(call("real2", "SetReal", comp, addr_vr, len(vrs), addr_val), "set parameters")
            self._check(call("p", "EnterInitializationMode", comp), "enter initialisation mode")
            st["initialized"] = True
            self._check(call("p", "ExitInitializationMode", comp), "exit initialisation mode")

    def _check(self, status: int, what: str) -> None:
        if status > 1:
            msg = self.last_message or f"status {STATUS.get(status, status)}"
            raise FmuError(f"FMU {self.info.model_name} ({what}): {STATUS.get(status, status)}: {msg}")

    def exchange(self, values, t: float, h: float) -> tuple[float, ...]:
        """Inputs ``values`` (in value-reference order of ``inputs``) in at t, one
        communication step to t + h, the outputs out (a tuple)."""
        try:
            return self._stepper.exchange(values, t, h)  # type: ignore[union-attr]
        except native.FmiStatus as exc:
            stage, status = exc.args
            what = (f"set inputs at t = {t:.3f} s", f"doStep at t = {t:.3f} s", f"get outputs at t = {t + h:.3f} s")
            self._check(status, what[stage])
            raise
        except native.Aborted as exc:
            self._abandon()
            raise abort_error(exc.args, self.info.model_name, "doStep", t) from None

    def get(self, vrs: Sequence[int]) -> list[float]:
        vr_t = ctypes.c_uint32 if self.v3 else ctypes.c_uint
        arr_vr = (vr_t * len(vrs))(*vrs)
        val = (ctypes.c_double * len(vrs))()
        kind, fn = ("real3", "GetFloat64") if self.v3 else ("real2", "GetReal")
        status = self._call(kind, fn, self.component, ctypes.addressof(arr_vr), len(vrs), ctypes.addressof(val))
        self._check(status, "get")
        return list(val)

    def close(self) -> None:
        """Terminate and free the instance, unload the library, remove the extracted folder."""
        self.component = None
        self._finalizer()
