"""
The body and its inputs: validated scenarios, shapes, spin states, units, rotations.

Also the equations of motion and their invariants, and the limits of accepted input.
"""
