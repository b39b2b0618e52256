"""Planning: single shooting over gait parameters ([COBRA] "shooting method to find optimal u_ref").

The wing is read in this order: ``problem`` (decision vector, bounds, goal, the common start, one
rollout), ``cost`` (the cost of a rollout), ``search`` (compass search or differential evolution,
run on any executor), ``results`` (the params JSON and its replay), ``checkpoint`` (the params
JSON written as the search goes).

The closed loop (``cobra-ref push``) is read after it: ``primitives`` (the per-period motion
primitives and the joint reference they chain into), ``locomotion`` (where each primitive takes the
robot alone), ``facing`` (which way the robot can push the box, and the turns that face it towards
the target), ``choices`` (the candidates of one re-plan), ``receding`` (the receding-horizon planner),
``reasons`` (what a push says of its task, up front and when it gives up), ``plan_file`` (its plan
JSON, written and read back), ``benchmark`` (its goals around the box).
"""

from ..infra.executors import SerialExecutor
from .cost import evaluate, shooting_cost
from .problem import (DECISION, DEFAULTS, DecisionSpace, ShootingError, ShootingProblem, Weights, make_problem,
                      middle_pose, rollout, start_state)
from .checkpoint import Checkpoint
from .results import load_result, problem_from_dict, problem_to_dict, replay, write_result
from .search import SearchOptions, compass_search, differential_evolution_search, optimize, optimize_gait

__all__ = ["Checkpoint", "DECISION", "DEFAULTS", "DecisionSpace", "SearchOptions", "SerialExecutor", "ShootingError",
           "ShootingProblem", "Weights", "compass_search", "differential_evolution_search", "evaluate", "load_result",
           "make_problem", "middle_pose", "optimize", "optimize_gait", "problem_from_dict", "problem_to_dict",
           "replay", "rollout", "shooting_cost", "start_state", "write_result"]
