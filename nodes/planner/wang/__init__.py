"""Wang's improved APF and his traditional APF baseline."""
