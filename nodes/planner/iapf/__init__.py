"""IAPF (car-scale road planner on obstacle tracks)."""
