"""Verification of an allocation: Monte Carlo / Latin hypercube on the first-order or the nonlinear
model (:mod:`.montecarlo`, ``verify``), and the nonlinear error model's worst vertex and interval
sampling (:mod:`.nonlinear`)."""
