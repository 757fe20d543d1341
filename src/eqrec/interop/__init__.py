"""Bridges to other control libraries (optional extras): :mod:`eqrec.interop.python_control`."""
