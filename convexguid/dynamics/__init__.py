"""Equations of motion: rigid body (attitude); later Clohessy-Wiltshire (relative orbit)."""
