"""The viewer node: a namespace's traffic served to Foxglove (``python -m nodes.viewer``, ``papf view``)."""
