"""Measure a scene's speed/accuracy trade and recommend the cheapest settings that meet a
target error (``pwc trade``; docs/trade.md).

Modules: :mod:`trade.knobs` (what may be traded, the reference's settings),
:mod:`trade.measure` (one timed render), :mod:`trade.metrics` (image and geometric
errors), :mod:`trade.sweep` (reference, sweep, combination, Pareto front),
:mod:`trade.report` (Markdown, HTML, plots, the recommended scene file),
:mod:`trade.command` (the subcommand).
"""
