"""The bench reports: plots, pages, the comparison page."""
from artibus.report.pages import *   # noqa: F401,F403
