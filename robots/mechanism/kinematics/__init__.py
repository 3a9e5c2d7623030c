"""Kinematics of a described mechanism: the frame tree, placements, the compiled serial chain."""
