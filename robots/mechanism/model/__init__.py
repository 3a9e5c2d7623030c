"""The error model of a described mechanism: its sources, joint configurations, clearances, random sources, identifiability."""
