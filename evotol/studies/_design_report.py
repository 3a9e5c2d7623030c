"""What the two design studies (deng2012-tolsynth, deng2012-dimsynth) share: the parallel-coordinate
section of their reports and the counts that section shows (computed in ``compute`` so that the
JSON states them)."""
from __future__ import annotations

from evotol.design.filtering import DesignStudy
from evotol.reporting.parcoords import add_parcoords, preset_table_rows
from evotol.reporting.parcoords_lines import DEFAULT_MAX_DRAWN, drawn_lines, parcoords_frame

PRESET_HEADER = ["preset", "thesis", "query", "kept", "kept levels (mm)"]


def parcoords_counts(study: DesignStudy, extra, axes) -> dict:
    """``presets_shown_in_report`` and ``report_lines`` of the page :func:`parcoords_section` draws:
    the same frame (entries + ``extra``), preset filters and drawn sample as ``add_parcoords``."""
    frame = parcoords_frame(study, None, extra)
    presets = list(study.presets.values())
    shown = {p.name: study.filter(p, among=frame) for p in presets}
    drawn = drawn_lines(frame, axes, presets, study, DEFAULT_MAX_DRAWN, 0, kept={n: r.kept.index for n, r in shown.items()})
    return {"presets_shown_in_report": {n: r.count for n, r in shown.items()},
            "report_lines": {"entries": int(len(frame)), "drawn_by_default": int(len(drawn))}}


def parcoords_section(rep, study: DesignStudy, extra, axes, intro: str, presets_heading: str) -> None:
    """The interactive parallel coordinates (coloured by p_max, ``extra`` = NSGA-II entries on top)
    and the table of the presets' kept entries and levels."""
    rep.heading("Parallel coordinates")
    rep.text(intro)
    add_parcoords(rep, study, axes=axes, color="p_max_mm", extra=extra, div_id="pc")
    rep.heading(presets_heading)
    rep.table(preset_table_rows(study), PRESET_HEADER)
