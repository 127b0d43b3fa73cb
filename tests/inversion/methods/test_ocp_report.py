"""The optimal-control summary's solver line: its status and iteration count said once."""

from __future__ import annotations

import control

from inversion import OptimalControl, Problem, Sampling, invert, trajectory_from_spec
from inversion.chain.hpipm import ChainSolution


def test_an_accepted_stall_s_iterations_are_counted_once_and_a_solve_s_as_before() -> None:
    result = invert(Problem(control.tf([-1.0, 2.0], [1.0, 4.0, 3.0]), trajectory_from_spec("smoothstep:1:8:6"),
                            sampling=Sampling(period=0.02)), method="ocp")
    method = OptimalControl()
    solved = [line for line in method.report(result.summary) if line.lstrip().startswith("HPIPM")]
    o = result.summary["ocp"]
    assert len(solved) == 1 and f"{o['status']} in {o['iterations']} iterations, {o['seconds']:.2f} s" in solved[0], solved
    # an accepted stall: HPIPM's own message (ChainSolution.message) already counts the iterations
    stall = ChainSolution([], [], 1, 120, {"stat": 2e-9, "eq": 1e-12, "ineq": 1e-12, "comp": 3e-9}, 1e-10).message
    summary = {**result.summary, "ocp": {**o, "status": stall, "iterations": 120}}
    line = next(line for line in method.report(summary) if line.lstrip().startswith("HPIPM"))
    assert line.count("120 iterations") == 1 and "HPIPM: " not in line and "iteration limit reached after 120" in line, line
