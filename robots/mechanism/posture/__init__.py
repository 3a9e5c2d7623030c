"""The posture a mechanism holds: inverse geometry, the declared working mode, the posture over a task."""
