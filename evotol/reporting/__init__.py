"""HTML reports: read results, never compute physics (STYLE.md)."""
from evotol.reporting.html import Report, table_html, write_json

__all__ = ["Report", "table_html", "write_json"]
