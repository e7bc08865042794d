"""One throw's catch: mount, arm, intercept, closing, soft stop and turn, the self-check on
the rows, the planner, what a plan is, and the API (``api``)."""
