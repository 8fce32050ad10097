"""The report kit: what every experiment's report (and a plugin's) is built from, so that the
three papers' reports and a plugin's judge, tabulate and draw their results one way:
:mod:`.verdicts` sets a reproduced number or claim against the paper's; figures are data
before they are drawing.

An experiment declares each figure's :class:`~trackfuse.reportkit.spec.Plot` (which metric
against which axis, grouped by algorithm, faceted how, with which interval and reference
lines) on its :class:`~trackfuse.experiments.base.FigureSpec`, the display labels of its
parameters and metrics on :class:`~trackfuse.experiments.base.Param`/``Metric`` and the
look of each algorithm (:class:`~trackfuse.reportkit.looks.Look`) on the ``Experiment``.
One renderer (:mod:`.render`) draws every declared figure in one journal style and layout
(:mod:`.style`): 3.5 in or 7.16 in wide, at most 8.5 in tall, no text below 7 pt, TrueType
fonts in PDFs. A report module that only draws declared figures is
:mod:`trackfuse.reportkit.declared` itself. The pure modules (:mod:`.spec`, :mod:`.looks`,
:mod:`.typography`) load no matplotlib, so an experiment's declaration can use them.
"""
