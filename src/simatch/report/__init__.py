"""Match and tournament reports: what happened, as plots a coach reads at a glance (docs/report.md)."""
