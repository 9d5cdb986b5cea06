#!/usr/bin/env python3
"""Writes a particle file with its particle lines in reverse order (comments first, as they were):
the same body in another order, for the tests of order-independent region rules.

    reverse_particle_file.py IN OUT
"""
import sys

with open(sys.argv[1]) as f:
    lines = f.readlines()
comments = [l for l in lines if l.lstrip().startswith("#") or not l.strip()]
particles = [l for l in lines if l.strip() and not l.lstrip().startswith("#")]
if not particles:
    sys.exit("reverse_particle_file: no particle line in " + sys.argv[1])
with open(sys.argv[2], "w") as f:
    f.writelines(comments + particles[::-1])
