"""Predictive APF (Szczepanski et al. 2022)."""
