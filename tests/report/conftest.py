"""Report tests draw headless: matplotlib's Agg backend, figures read back through their axes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
