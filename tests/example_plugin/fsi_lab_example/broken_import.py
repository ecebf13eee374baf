"""A plugin whose import fails, as one with a missing dependency would."""

import fsi_lab_example_missing_dependency  # noqa: F401 - absent on purpose: the import fails
