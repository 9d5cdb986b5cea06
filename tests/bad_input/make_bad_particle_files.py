#!/usr/bin/env python3
"""Writes the particle files of the untrusted-input tests (tests/untrusted_inputs.cmake) into DIR,
each tests/scenes/tension_block_particles.txt with one defect:

    stray.txt          one more particle at (-0.9, -0.9), far beyond any horizon (no neighbour),
                       within the scene's 'left' region (its x prescribed, its y free)
    repeated.txt       the fifth particle's line twice (two particles at one position)
    hex.txt            a coordinate written in hexadecimal (0x1p-5)
    tiny_volume.txt    a volume of 1e-320 (a denormal number)
    negative_block.txt a block id of -2
    fifo.txt           a FIFO (named pipe), not a file: opening it would wait for a writer
    folder.txt/        a folder

    usage: make_bad_particle_files.py DIR
"""
import os
import shutil
import sys

out = sys.argv[1]
src = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes", "tension_block_particles.txt")
os.makedirs(out, exist_ok=True)
with open(src) as f:
    lines = f.read().splitlines()
data = [k for k, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]


def write(name, body):
    with open(os.path.join(out, name), "w") as f:
        f.write("\n".join(body) + "\n")


def with_field(column, value):
    body = list(lines)
    parts = body[data[4]].split()
    parts[column] = value
    body[data[4]] = " ".join(parts)
    return body


write("stray.txt", lines + ["-0.9 -0.9 0.0 2.5e-03 1"])
write("repeated.txt", lines + [lines[data[4]]])
write("hex.txt", with_field(0, "0x1p-5"))
write("tiny_volume.txt", with_field(3, "1e-320"))
write("negative_block.txt", with_field(4, "-2"))
fifo = os.path.join(out, "fifo.txt")
if os.path.exists(fifo):
    os.remove(fifo)
os.mkfifo(fifo)
shutil.rmtree(os.path.join(out, "folder.txt"), ignore_errors=True)
os.makedirs(os.path.join(out, "folder.txt"))
print("wrote the bad particle files in " + out)
