"""Run recordings (docs/recording.md): write, read, recover and replay MCAP files.

- :class:`~nodes.recorder.writer.RunWriter` — crash-safe MCAP writer (one channel per key);
- :func:`~papf.recording.reader.open_recording` / :func:`~papf.recording.reader.iter_messages`;
- :func:`~papf.recording.recover.recover` — salvage a truncated file;
- :func:`~papf.recording.replay.replay` — republish with the recorded timing.

Pure: nothing here imports Zenoh (the recorder node is ``python -m nodes.recorder``).
See docs/recording.md.
"""

from nodes.recorder.writer import RunWriter, WriterStats, peek_stamp, type_for_key
from papf.recording.reader import (
    RawMessage,
    RecordedMessage,
    Recording,
    iter_messages,
    key_matches,
    open_recording,
    read_metadata,
)
from papf.recording.recover import RecoverStats, recover
from papf.recording.replay import ReplayStats, remap_key, replay

__all__ = [
    "RawMessage", "RecordedMessage", "Recording", "RecoverStats", "ReplayStats", "RunWriter",
    "WriterStats", "iter_messages", "key_matches", "open_recording", "peek_stamp",
    "read_metadata", "recover", "remap_key", "replay", "type_for_key",
]
