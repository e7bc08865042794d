"""Catch: a thrown ball met by the palm, stopped softly and held by the closing fingers.

By concept:

* ``flight/`` -- the ball: its path (``path``: ``Flight``, ``predict_throw``, the balls),
  the drag table (``dragtable``), the fit of a flight to observations (``observe``; live,
  one observation at a time: ``livefit``, ``tablesums``), simulated camera (``camera``);
* ``plan/`` -- one throw's catch: the mount, the arm, the intercept, the closing, the soft
  stop and the wrist's turn, the self-check on the rows, the planner (``planner``:
  ``CatchPlanner``), what a plan is (``results``, ``reasons``) and the API (``api``);
* ``live/`` -- the catch re-planned at every observation (``session``: ``CatchSession``;
  ``search``, ``motion``);
* ``grasp`` -- the contact forces that stop and hold the ball (the grasp QP; also used by
  ``planner.hand.grip``);
* ``summary``, ``livecli`` -- ``cli.py catch`` (moving to ``planner.cli``).

The public surface (imported on first use, so that ``import planner.catch`` stays light):
``plan_catch``, ``plan_throw``, ``write_plan``, ``get_planner``, ``CatchSession``,
``CatchPlan``, ``CatchResult``, ``CatchReason``, ``Reason``.
"""

from __future__ import annotations

from planner.lazy import lazy_names

_API = {
    "plan_catch": "planner.catch.plan.api",
    "plan_throw": "planner.catch.plan.api",
    "write_plan": "planner.catch.plan.api",
    "get_planner": "planner.catch.plan.api",
    "CatchSession": "planner.catch.live.session",
    "CatchPlan": "planner.catch.plan.results",
    "CatchResult": "planner.catch.plan.results",
    "CatchReason": "planner.catch.plan.reasons",
    "Reason": "planner.catch.plan.reasons",
}

__all__ = ["CatchPlan", "CatchReason", "CatchResult", "CatchSession", "Reason", "get_planner",
           "plan_catch", "plan_throw", "write_plan"]

__getattr__ = lazy_names(__name__, _API)
