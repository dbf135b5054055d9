"""Classic APF (PAPF paper eq. 2)."""
