"""The ball in flight: its path, the drag table, fits to observations (planned and live),
the simulated camera."""
