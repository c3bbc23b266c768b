"""Dataset converters between the field's robot-learning formats and the DMBN layout.

`python3 -m dmbn_convert lerobot|robomimic|to-lerobot ...` (see README.md). The readers
(`lerobot`, `robomimic`, `dmbn`) yield episodes; `writer.DmbnWriter` and `to_lerobot` write
them, each into a temporary sibling folder renamed into place at the end, so that a failed
conversion leaves nothing behind.
"""


class ConvertError(Exception):
    """An expected failure (bad input, existing output): printed as `error: ...`, exit 2."""
