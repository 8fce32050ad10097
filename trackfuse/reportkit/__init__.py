"""The report kit: what every experiment's report (and a plugin's) is built from, so that the
three papers' reports and a plugin's judge, tabulate and draw their results one way:
:mod:`.verdicts` sets a reproduced number or claim against the paper's."""
