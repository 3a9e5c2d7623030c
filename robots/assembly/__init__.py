"""Assembly functions as error models: ordinary mechanical assemblies behind the robot protocol.

* :mod:`.function` -- :class:`AssemblyFunction`: responses ``y_k = f_k(x)`` of the nominal
  dimensions, their derivatives (complex step, central differences) and the robot protocol
  (normalised response errors in row 2 of the error twist);
* :mod:`.linear_stack` -- :class:`LinearStack`: a linear stack ``y_k = Σ_j a_kj x_j``, and its worst
  case and RSS (:func:`worst_case_deviation`, :func:`rss_half_width`), which the stack analysis uses too;
* :mod:`.study_file` -- :func:`resolve` and :func:`assembly_from_spec`: the ``[robot]`` table of a
  study file that names an assembly function.

All dimensions and tolerances are SI (m) unless a source declares ``unit="rad"``.
"""
from evotol.robots.assembly.function import ROW, AssemblyFunction
from evotol.robots.assembly.linear_stack import LinearStack, rss_half_width, worst_case_deviation, zone_extremes
from evotol.robots.assembly.study_file import assembly_from_spec, resolve

__all__ = ["AssemblyFunction", "LinearStack", "resolve", "assembly_from_spec", "ROW", "worst_case_deviation",
           "rss_half_width", "zone_extremes"]
