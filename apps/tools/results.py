"""Reading depthfem results files with h5py: the one place the tools learn the layout
(documented dataset by dataset in apps/README.md).

    from results import Results, ResultsError
    with Results("out.h5") as r:
        loads = r.series("load")          # one value per completed step
        x = r.step(r.num_steps - 1)["x"]  # #nodes x 3 positions of the last step
        print(r.status, r.timing())

A step is a row of the datasets of /steps; /steps/index says which steps are complete (a killed
run's datasets may hold one more row, of a step never completed). The file is opened as an HDF5
single-writer/multiple-reader reader, so it can be read while depthfem writes it and after a
killed run.
"""

import json

import h5py
import numpy as np


class ResultsError(Exception):
    """A file that is not a readable depthfem results file, or a step it does not hold."""


class Step:
    """The datasets of one completed step (or of the reference state), by name: step["x"]."""

    def __init__(self, results, row):
        self._results, self.row = results, row

    def __contains__(self, name):
        return name in self._results.f["steps"]

    def __getitem__(self, name):
        if name == "residuals":
            return self._results.residuals(self.row)
        return self._results.f["steps"][name][self.row]


class Results:
    """An open results file."""

    def __init__(self, path):
        self.path = path
        try:
            self.f = h5py.File(path, "r", swmr=True)
        except OSError as e:
            raise ResultsError(f"{path}: cannot be opened as an HDF5 file ({e})") from None
        if not all(group in self.f for group in ("mesh", "run", "steps")):
            self.f.close()
            raise ResultsError(f"{path}: not a depthfem results file (no /mesh, /run or /steps)")
        if "index" not in self.f["steps"]:
            self.f.close()
            raise ResultsError(f"{path}: written by an older depthfem (steps as groups)")
        self.index = self.f["steps/index"][:]
        self.num_steps = len(self.index)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self.f.close()

    @property
    def status(self):
        """'running', 'completed' or 'failed'."""
        return self.f["run/status"][()].decode()

    @property
    def message(self):
        return self.f["run/message"][()].decode()

    @property
    def analysis(self):
        return self.f["run"].attrs["analysis"]

    def scene(self):
        """The scene file of the run, parsed."""
        return json.loads(self.f["run"].attrs["scene"])

    def has(self, name):
        """Whether the run writes /steps/NAME."""
        return name in self.f["steps"]

    def series(self, name):
        """/steps/NAME of every completed step: one row per step (for the residuals, which are
        not one row a step, see residuals and last_residuals)."""
        if name == "residuals":
            raise ValueError("/steps/residuals holds residual_count values per step")
        return self.f["steps"][name][: self.num_steps]

    def row_of(self, index):
        """The row of step `index`."""
        rows = np.flatnonzero(self.index == index)
        if not len(rows):
            span = f"steps {self.index[0]} to {self.index[-1]}" if self.num_steps else "no steps"
            raise ResultsError(f"{self.path}: no step {index} ({span})")
        return int(rows[0])

    def step(self, row):
        """The datasets of the step in row `row` (negative: from the end)."""
        if not -self.num_steps <= row < self.num_steps:
            raise ResultsError(f"{self.path}: no step row {row} ({self.num_steps} steps)")
        return Step(self, row % self.num_steps)

    def reference(self):
        """The datasets of the state before the first step."""
        return self.f["reference"]

    def residuals(self, row):
        """The residuals of the Newton iterates of the step in row `row`."""
        counts = self.series("residual_count")
        start = int(counts[:row].sum())
        return self.f["steps/residuals"][start : start + int(counts[row])]

    def last_residuals(self):
        """The residual of the last Newton iterate of every step (nan for a step without)."""
        counts = self.series("residual_count")
        ends = np.cumsum(counts)
        values = self.f["steps/residuals"][: int(ends[-1])] if self.num_steps else np.zeros(0)
        return np.array([values[e - 1] if c else np.nan for c, e in zip(counts, ends)])

    def timing(self):
        """{phase: seconds} in the order the run wrote them."""
        names = [n.decode() for n in self.f["timing/phases"][:]]
        return dict(zip(names, self.f["timing/seconds"][: len(names)]))
