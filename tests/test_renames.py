"""Renamed names keep working under their old ones, each use with a DeprecationWarning naming the
new one: the history's increment counter ``step`` (now ``increment``: in results, rows, history
files and checkpoints written before), the number of increments ``n_steps`` (now ``n_increments``:
step settings and scene parameters), and the classes ``Run`` (``RunState``), ``RunResult``
(``StepOutcome``) and ``Increment.step`` (``number``)."""
import dataclasses
import json

import numpy as np
import pytest

from comove_dolfinx.io.csv_tables import Columns, current_names, read_history


def test_the_increment_column_reads_under_its_old_name(tmp_path):
    from comove_dolfinx.job import Results
    rows = [Columns(increment=k, time=0.5 * k) for k in (1, 2, 3)]
    res = Results(["increment", "time"], rows=rows)
    with pytest.warns(DeprecationWarning, match="'step' is now called 'increment'"):
        np.testing.assert_array_equal(res["step"], [1, 2, 3])
    with pytest.warns(DeprecationWarning, match="'step' is now called 'increment'"):
        assert res.last["step"] == 3
    with pytest.raises(KeyError, match="no column 'stage'"):
        res["stage"]
    # a history written before the rename is read under the new name
    old = tmp_path / "history.csv"
    old.write_text("step,time,load\n1,0.5,5\n2,1,10\n")
    hist = read_history(old, origin=True)
    assert list(hist) == ["increment", "time", "load"]
    np.testing.assert_array_equal(hist["increment"], [0, 1, 2])
    with pytest.warns(DeprecationWarning):
        np.testing.assert_array_equal(hist["step"], [0, 1, 2])
    # a probe's own column "step" beside the counter keeps its name
    assert current_names(["increment", "step"]) == {"increment": "increment", "step": "step"}


def test_the_number_of_increments_under_its_old_name():
    from comove_dolfinx.presets import get_scene
    from comove_dolfinx.solver import StepSettings
    with pytest.warns(DeprecationWarning, match="StepSettings.n_steps is now called n_increments"):
        settings = StepSettings(n_steps=7, t_end=0.5)
    assert settings.n_increments == 7 and settings.t_end == 0.5
    with pytest.warns(DeprecationWarning, match="n_steps is now called n_increments"):
        assert settings.n_steps == 7
    with pytest.warns(DeprecationWarning):
        assert dataclasses.replace(settings, n_steps=3).n_increments == 3
    with pytest.warns(DeprecationWarning, match="the scene parameter n_steps is now called n_increments"):
        scene = get_scene("elastica", ["n_steps=4"])
    assert scene.n_increments == 4 and scene.steps()[0].n == 4
    with pytest.warns(DeprecationWarning, match="Scene.n_steps is now called n_increments"):
        assert scene.n_steps == 4


def test_the_renamed_classes():
    import comove_dolfinx.job as job
    import comove_dolfinx.solver as solver
    with pytest.warns(DeprecationWarning, match="job.Run is now called RunState"):
        assert job.Run is job.RunState
    with pytest.warns(DeprecationWarning, match="RunResult is now called StepOutcome"):
        assert solver.RunResult is solver.StepOutcome
    inc = solver.Increment(4, 0.5, 3, 0.1)
    with pytest.warns(DeprecationWarning, match="Increment.step is now called Increment.number"):
        assert inc.step == inc.number == 4


def test_a_checkpoint_written_before_the_rename_restarts(tmp_path):
    """A checkpoint whose rows and loop counter still say ``step`` (as those written before the
    rename do) restarts to the history of the uninterrupted run."""
    from comove_dolfinx.io.checkpoint import Checkpoint
    from test_api import _stretch_and_release
    job, _ = _stretch_and_release()
    full = job.run()
    folder = tmp_path / "checkpoint"
    stopped, _ = _stretch_and_release(Checkpoint(folder), stop_after=4)
    with pytest.raises(RuntimeError, match="stopped by the test"):
        stopped.run()
    meta = json.loads((folder / "meta.json").read_text())
    meta["rows"] = [{("step" if k == "increment" else k): v for k, v in row.items()} for row in meta["rows"]]
    meta["resume"]["step"] = meta["resume"].pop("increment")
    (folder / "meta.json").write_text(json.dumps(meta))
    again, _ = _stretch_and_release(Checkpoint(folder))
    res = again.run(restart=folder)
    assert res.completed and res.newton_its == full.newton_its
    np.testing.assert_array_equal(res["increment"], np.arange(1, len(full) + 1))
    np.testing.assert_allclose(res["end_fx"], full["end_fx"], rtol=0, atol=1e-12 * abs(full["end_fx"]).max())
