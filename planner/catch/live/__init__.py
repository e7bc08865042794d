"""The live catch: the session re-planned at every observation, its intercept search and
the arm's re-aims."""
