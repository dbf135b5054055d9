"""Launching: launch profiles resolved into processes, the supervisor, the embedded router,
the run's start/end sequence and its outcome (``papf run``, ``papf launch``)."""
