"""The one loop of a study's work: methods, comparisons and Monte Carlo checks, each a named step run
under the study's Ctrl-C (issue 15, issue 39).

Every kind of study (the robot studies, stacks, analyses) runs its work through :func:`run_steps`:
a Ctrl-C stops the running step (a GA or NSGA-II keeps its best so far), the remaining steps are
skipped unless ``keep_going``, and what ran is kept and written, with the stopped and skipped steps
named in the summary (:class:`StepLog`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Callable

logger = logging.getLogger(__name__)


@dataclass
class StepLog:
    """What a study's steps did under Ctrl-C.

    Parameters
    ----------
    keep_going : bool
        After a Ctrl-C, still run the remaining steps.
    stopped : list of str
        Steps a Ctrl-C stopped.
    skipped : list of str
        Steps not run after a Ctrl-C.
    """

    keep_going: bool = False
    stopped: list = field(default_factory=list)
    skipped: list = field(default_factory=list)

    def interruption(self) -> dict | None:
        """The summary's ``interruption`` block, or None when nothing was stopped.

        Returns
        -------
        dict or None
            ``stopped``, ``skipped`` (step names) and ``keep_going``.
        """
        if not self.stopped:
            return None
        return {"stopped": list(self.stopped), "skipped": list(self.skipped), "keep_going": self.keep_going}


def run_steps(steps: dict, ctrl_c, log: StepLog, results: dict | None = None, label: str = "",
              say: bool = True) -> dict:
    """Run named steps in order under a :class:`evotol._runtime.interrupt.CtrlC` (module docstring).

    Parameters
    ----------
    steps : dict of str to callable
        Step name -> a function of no argument returning the step's result (None: nothing kept). A
        step may read ``results`` (the steps before it).
    ctrl_c : evotol._runtime.interrupt.CtrlC
        The study's Ctrl-C handler (its ``count``).
    log : StepLog
        Where stopped and skipped steps are recorded.
    results : dict, optional
        Filled in place with each finished step's result (a new dict by default).
    label : str, optional
        Prefix of the names recorded in ``log`` (e.g. ``"verify "``).
    say : bool, optional
        Log a line as each step starts.

    Returns
    -------
    dict
        ``results``.
    """
    results = {} if results is None else results
    for name, step in steps.items():
        if ctrl_c.count and not log.keep_going:
            log.skipped.append(label + name)
            continue
        if say:
            logger.info("%s%s ...", label, name)
        before = ctrl_c.count
        try:
            value = step()
            if value is not None:
                results[name] = value
        except KeyboardInterrupt:
            ctrl_c.count = max(ctrl_c.count, before + 1)
        finally:
            if ctrl_c.count > before:
                log.stopped.append(label + name)
    return results
