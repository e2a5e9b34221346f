"""Test-wide set-up: keep Rerun's and matplotlib's config out of the user's home."""

import atexit
import os
import shutil
import signal
import tempfile

import pytest

_TMP = tempfile.mkdtemp(prefix="ego-tests-")
atexit.register(shutil.rmtree, _TMP, True)  # each process (pytest, an xdist worker) its own
# SB3_LOGDIR: stable-baselines3's default logger makes a folder there on every ``learn``
for var in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "MPLCONFIGDIR", "SB3_LOGDIR"):
    os.environ.setdefault(var, os.path.join(_TMP, var.lower()))
os.environ.setdefault("RERUN_ANALYTICS", "false")


@pytest.fixture(autouse=True)
def _signal_handlers_restored():
    """Something in-process (``ego._entry`` answering a command, a module-scoped fixture's
    teardown) can leave SIGINT/SIGTERM ignored; a later test's run would then never see its
    Ctrl-C, nor would the processes it starts (an ignored signal is inherited). Each test
    starts with Python's default handlers where they were ignored, and gets the old ones back."""
    saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    if saved[signal.SIGINT] is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if saved[signal.SIGTERM] is signal.SIG_IGN:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    yield
    for sig, handler in saved.items():
        if signal.getsignal(sig) is not handler:
            signal.signal(sig, handler)


#: tests that take seconds without SUMO: they start processes (``python -m ego`` as a user
#: runs it, a Ray cluster, a C compiler for FMUs, netconvert) or walk every module; the fast
#: loop (``pytest -m "not sumo and not slow"``) leaves them to the whole suite
SLOW_TESTS = {
    "tests/highway_env/test_highway_env_video.py": {"test_mp4_is_written_with_imageio_ffmpegs_own_binary"},
    "tests/control/test_signal_units.py": {"test_every_signal_has_a_declared_unit"},
    "tests/control/test_cascade.py": {"test_one_member_and_one_drive_agree_with_the_batch"},
    "tests/control/test_fuzzy_engine.py": {"test_surface_is_odd_and_saturates"},
    "tests/control/test_fuzzy_pid.py": {
        "test_gains_are_the_scales_at_zero_error_and_the_report_variant_uses_report_scales",
        "test_large_error_raises_kp_and_lowers_ki",
    },
    "tests/fmi/test_export_fmu.py": {
        "test_bad_export_arguments_are_one_line",
        "test_the_exported_fmu_steps_as_egos_model",
        "test_the_sources_inside_compile_on_their_own",
    },
    "tests/fmi/test_fmu_checks.py": {
        "test_a_step_the_fmu_cannot_take",
        "test_bad_mappings",
        "test_fmi_1",
        "test_invalid_model_description",
        "test_missing_file",
        "test_missing_output_names_the_outputs",
        "test_model_exchange_only",
        "test_no_model_description",
        "test_not_a_zip",
        "test_unknown_and_bad_parameters",
        "test_unknown_input_signal",
        "test_windows_only",
        "test_wrong_task",
    },
    "tests/gym/test_env.py": {"test_only_ego_gym_imports_gymnasium"},
    "tests/models/test_longitudinal.py": {"test_the_actuator_lag_adds_a_first_order_pole"},
    "tests/openscenario/test_xosc_corpus.py": {
        "test_bad_road_conversion",
        "test_generated_valid_file_runs",
        "test_hand_written",
    },
    "tests/openscenario/test_xosc_roads.py": {"test_clothoid_curvature", "test_conversion_is_cached"},
    "tests/sim/test_registry.py": {"test_no_libsumo_import_outside_ego_sumo"},
    "tests/sumo/test_network.py": {"test_committed_network_matches_a_rebuild"},
    "tests/sweep/test_ray_cluster.py": {
        "test_a_sigkilled_sweep_leaves_none_of_its_processes_on_any_node",
        "test_a_sigkilled_sweep_on_a_private_ray_leaves_no_ray_process",
        "test_a_sweep_on_three_nodes_has_every_row_with_its_node",
        "test_an_address_without_a_ray_head_is_one_line_within_seconds",
        "test_losing_a_worker_node_mid_sweep_costs_only_its_runs_one_retry",
        "test_tune_with_sumo_costs_on_the_cluster",
    },
    "tests/sweep/test_spec.py": {"test_the_cli_reports_a_bad_spec_in_one_line_and_writes_nothing"},
    "tests/test_bad_inputs.py": {"test_as_a_subprocess_bad_input_exits_2_with_one_line"},
    "tests/test_bad_outputs.py": {
        "test_a_signal_in_the_first_second_is_exit_130_without_a_traceback",
        "test_a_double_ctrl_c_never_leaves_a_broken_recording",
        "test_a_run_whose_output_fills_the_disk_prints_its_metrics_and_one_line",
        "test_a_sweep_recording_every_run_on_a_full_disk_keeps_the_metrics",
        "test_a_sweep_whose_results_fill_the_disk_stops_in_one_line_without_hanging",
        "test_stdout_on_a_full_device_is_one_line",
        "test_sweep_results_that_cannot_take_the_new_rows_are_refused_before_running",
        "test_the_shipped_files_survive_train_and_tune_pointed_at_them",
        "test_train_tune_compare_on_a_full_disk_end_in_one_line",
    },
    "tests/test_cli.py": {
        "test_bad_input_is_one_line_and_exit_2",
        "test_bad_seeds_and_output_places_fail_at_once_writing_nothing",
        "test_help_explains_the_run_command",
        "test_list_json_gives_every_scenario_its_metrics_and_columns_with_units",
        "test_list_names_every_parameter_with_default_and_unit",
    },
    "tests/test_compare.py": {"test_compare_shows_what_the_scenario_declares_with_units"},
    "tests/test_compare_signals.py": {"test_ctrl_c_in_an_in_process_comparison_stops_it_and_keeps_what_finished"},
    "tests/test_compare_variants.py": {"test_variants_are_labelled_as_given_everywhere"},
    "tests/test_docs.py": {"test_a_bad_page_or_table_is_one_line_and_exit_2"},
    "tests/test_export.py": {"test_pandas_is_imported_only_when_asked"},
    "tests/test_layers.py": {
        "test_the_lower_packages_never_import_scenarios",
        "test_no_module_imports_from_a_layer_above_it",
        "test_every_unit_of_ego_has_a_layer",
    },
    "tests/test_resolve.py": {"test_compare_resolves_each_controller_once_and_its_workers_never"},
}


def pytest_collection_modifyitems(config, items):
    """A highway-env simulation and a Ray instance take seconds to start: such tests are
    ``slow`` too, so ``pytest -m "not sumo and not slow"`` is the fast loop."""
    slow = pytest.mark.slow
    for item in items:
        path = item.nodeid.split("::")[0]
        if getattr(item, "originalname", item.name) in SLOW_TESTS.get(path, ()):
            item.add_marker(slow)
        ray = (
            "ray_executor" in getattr(item, "fixturenames", ())
            or getattr(getattr(item, "callspec", None), "params", {}).get("engine") == "ray"
        )
        if item.get_closest_marker("highway_env") is not None or ray:
            item.add_marker(slow)


@pytest.fixture(scope="session")
def fuzzy_ready():
    """Compile report 000's rule base once (scikit-fuzzy builds its graph slowly)."""
    from ego.control import fuzzy

    return fuzzy.evaluator()


@pytest.fixture
def point_mass(monkeypatch):
    """The test-only point-mass scenario (no SUMO), registered for the test's duration."""
    from point_mass import PointMass

    from ego.scenarios import SCENARIOS

    monkeypatch.setitem(SCENARIOS, PointMass.name, PointMass)
    return PointMass
