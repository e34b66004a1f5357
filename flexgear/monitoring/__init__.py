"""Condition monitoring of simulated (or measured) gear signals, on any result file.

The layer between :mod:`flexgear.results` and :mod:`flexgear.app`: angular resampling from the
recorded shaft angles (:mod:`~flexgear.monitoring.order`), time-synchronous averages per shaft
(:mod:`~flexgear.monitoring.tsa`) with McFadden's planet-separation windows
(:mod:`~flexgear.monitoring.windows`), what a residual holds besides its own gear
(:mod:`~flexgear.monitoring.leaks`), the envelope of a
band (:mod:`~flexgear.monitoring.envelope`), the indicators RMS, crest factor, kurtosis, FM0,
FM4, NA4, M6A, M8A, energy ratio and sideband energy ratios
(:mod:`~flexgear.monitoring.indicators`), one result's analysis
(:mod:`~flexgear.monitoring.analysis`), its files and figures and the indicators against fault
severity over a batch (:mod:`~flexgear.monitoring.outputs`). Definitions and sources:
``docs/guide/monitoring.md``; command: ``flexgear monitor RESULT -o DIR``.

    from flexgear.monitoring import MonitorSettings, monitor, write_report
    report = monitor("out/mercury_1a/results.h5", MonitorSettings(signal="meshes/planet1-ring/normal_force"))
    report.shafts["sun"].indicators["fm4"]
"""
from .analysis import MonitorReport, MonitorSettings, monitor
from .outputs import severity_table, write_report, write_severity

__all__ = ["MonitorReport", "MonitorSettings", "monitor", "write_report", "severity_table", "write_severity"]
