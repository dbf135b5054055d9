"""Robot tools: the ROSbot emulator and the secure split's certificates and configs."""
