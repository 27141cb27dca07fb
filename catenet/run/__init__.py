"""Running a case: the runner (a case to its result file), advice after a run, and the
clock that tells start-up from solve time."""
