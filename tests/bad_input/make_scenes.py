#!/usr/bin/env python3
"""Writes the scenes of tests/badinput_scene.cmake that are easier made than kept: each is
tests/bad_input/tiny.xml (or the particle-file scene of tests/scenes) with one thing broken,
several of them as bytes that an editor or git would not show (NUL, Latin-1, a byte-order mark).

    make_scenes.py SOURCE_DIR OUT_DIR

SOURCE_DIR is tests/; OUT_DIR receives the scenes, a particle file with a NUL byte, and
xml/solvers/ holding one good and one broken linear-solver preset.
"""
import os
import shutil
import sys

TITLE = 'value="Tiny tension block (test)"'
LOAD = 'name="Value" type="Array(double)" value="{0.0, 1.0e3}"'
DIM = '<Parameter name="Dimension" type="int" value="2"/>'
STEPS = '<Parameter name="Load Steps" type="int" value="1"/>'
MATERIAL = '<ParameterList name="Material">'
LAST = '</ParameterList>\n'


def edited(text, old, new):
    assert text.count(old) >= 1, old
    return text.replace(old, new, 1)


def scenes(tiny):
    """name -> bytes of the scene file."""
    out = {
        "bom": b"\xef\xbb\xbf" + tiny.encode(),
        "xml_nan_load": edited(tiny, LOAD, LOAD.replace("{0.0, 1.0e3}", "{nan, nan}")),
        "xml_inf_load": edited(tiny, LOAD, LOAD.replace("{0.0, 1.0e3}", "{inf, 0}")),
        "xml_overflow_array": edited(tiny, 'value="{0.0, 0.0}"', 'value="{-1e999, 0.0}"'),
        "xml_nan_reference_stretch": tiny[: tiny.rindex(LAST)]
        + '  <ParameterList name="Reference"><Parameter name="Stretch" type="double" value="nan"/></ParameterList>\n' + LAST,
        "xml_int_overflow": edited(tiny, STEPS, STEPS.replace('value="1"', 'value="4294967297"')),
        "xml_text_between_elements": edited(tiny, MATERIAL, MATERIAL + "\n    stray text"),
        "xml_element_in_parameter": edited(tiny, DIM, DIM[:-2] + '><Parameter name="x" type="int" value="1"/></Parameter>'),
        "xml_nul_byte": edited(tiny, TITLE, TITLE.replace("Tiny", "Ti\0ny")),
        "xml_non_utf8_title": edited(tiny, TITLE, TITLE.replace("Tiny", "Tiny \udcff\udcfe")),
        "xml_latin1_name": tiny.replace('"tip"', '"t\u00eate"').encode("latin-1"),
        "xml_empty_file": "",
        "xml_whitespace_only": "  \n\t\n",
        "xml_comment_only": "<!-- a scene that holds nothing -->\n",
        # A custom linear-solver list whose perinox key 'Forcing Term' names no forcing term.
        "forcing_term_bogus": edited(tiny, '<Parameter name="Linear Solver Preset" type="string" value="direct"/>',
                                     '<Parameter name="Linear Solver Preset" type="string" value="custom"/>\n'
                                     '    <ParameterList name="Linear Solver">\n'
                                     '      <Parameter name="Forcing Term" type="string" value="Bogus"/>\n'
                                     '      <Parameter name="Linear Solver Type" type="string" value="Amesos2"/>\n'
                                     '    </ParameterList>'),
        # The kept MUMPS factorisation with a negative refactorisation threshold.
        "mumps_refactor_negative": edited(tiny, '<Parameter name="Linear Solver Preset" type="string" value="direct"/>',
                                          '<Parameter name="Linear Solver Preset" type="string" value="custom"/>\n'
                                          '    <ParameterList name="Linear Solver">\n'
                                          '      <Parameter name="Linear Solver Type" type="string" value="Belos"/>\n'
                                          '      <Parameter name="Preconditioner Type" type="string" value="MUMPS"/>\n'
                                          '      <ParameterList name="Preconditioner Types"><ParameterList name="MUMPS">\n'
                                          '        <Parameter name="Refactor Above Krylov Iterations" type="int" value="-3"/>\n'
                                          '      </ParameterList></ParameterList>\n'
                                          '    </ParameterList>'),
        # ... a negative allowance of excess applications.
        "mumps_excess_negative": edited(tiny, '<Parameter name="Linear Solver Preset" type="string" value="direct"/>',
                                        '<Parameter name="Linear Solver Preset" type="string" value="custom"/>\n'
                                        '    <ParameterList name="Linear Solver">\n'
                                        '      <Parameter name="Linear Solver Type" type="string" value="Belos"/>\n'
                                        '      <Parameter name="Preconditioner Type" type="string" value="MUMPS"/>\n'
                                        '      <ParameterList name="Preconditioner Types"><ParameterList name="MUMPS">\n'
                                        '        <Parameter name="Refactor Above Excess Applications" type="int" value="-1"/>\n'
                                        '      </ParameterList></ParameterList>\n'
                                        '    </ParameterList>'),
        # ... and an unknown precision for its factors.
        "mumps_precision_unknown": edited(tiny, '<Parameter name="Linear Solver Preset" type="string" value="direct"/>',
                                          '<Parameter name="Linear Solver Preset" type="string" value="custom"/>\n'
                                          '    <ParameterList name="Linear Solver">\n'
                                          '      <Parameter name="Linear Solver Type" type="string" value="Belos"/>\n'
                                          '      <Parameter name="Preconditioner Type" type="string" value="MUMPS"/>\n'
                                          '      <ParameterList name="Preconditioner Types"><ParameterList name="MUMPS">\n'
                                          '        <Parameter name="Factor Precision" type="string" value="Half"/>\n'
                                          '      </ParameterList></ParameterList>\n'
                                          '    </ParameterList>'),
        # ... renewed within a solve by a Krylov solver that is not flexible.
        "mumps_within_solve_not_flexible": edited(
            tiny, '<Parameter name="Linear Solver Preset" type="string" value="direct"/>',
            '<Parameter name="Linear Solver Preset" type="string" value="custom"/>\n'
            '    <ParameterList name="Linear Solver">\n'
            '      <Parameter name="Linear Solver Type" type="string" value="Belos"/>\n'
            '      <ParameterList name="Linear Solver Types"><ParameterList name="Belos">\n'
            '        <Parameter name="Solver Type" type="string" value="Block GMRES"/>\n'
            '      </ParameterList></ParameterList>\n'
            '      <Parameter name="Preconditioner Type" type="string" value="MUMPS"/>\n'
            '      <ParameterList name="Preconditioner Types"><ParameterList name="MUMPS">\n'
            '        <Parameter name="Refactor Within A Solve Above" type="int" value="40"/>\n'
            '      </ParameterList></ParameterList>\n'
            '    </ParameterList>'),
    }
    return {k: v if isinstance(v, bytes) else v.encode("utf-8", "surrogateescape") for k, v in out.items()}


def main():
    src, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(src, "bad_input", "tiny.xml"), encoding="utf-8") as f:
        tiny = f.read()
    for name, data in scenes(tiny).items():
        with open(os.path.join(out, name + ".xml"), "wb") as f:
            f.write(data)
    # A particle file with a NUL byte in its tenth line, and the scene that reads it.
    with open(os.path.join(src, "scenes", "tension_block_particles.txt"), "rb") as f:
        lines = f.read().split(b"\n")
    lines[9] = lines[9].replace(b" ", b" \0", 1)
    with open(os.path.join(out, "nul_particles.txt"), "wb") as f:
        f.write(b"\n".join(lines))
    with open(os.path.join(src, "scenes", "tension_block_file.xml"), encoding="utf-8") as f:
        scene = f.read()
    with open(os.path.join(out, "particle_file_nul.xml"), "w", encoding="utf-8") as f:
        f.write(edited(scene, 'value="tension_block_particles.txt"', 'value="nul_particles.txt"'))
    # The same particles with a token that is not a number in line 200 (in the last rank's slice of
    # the file when 3 ranks read it distributed), and the scene that reads them.
    with open(os.path.join(src, "scenes", "tension_block_particles.txt"), "rb") as f:
        lines = f.read().split(b"\n")
    lines[199] = lines[199].replace(b" ", b" 1.0x ", 1)
    with open(os.path.join(out, "late_garbage_particles.txt"), "wb") as f:
        f.write(b"\n".join(lines))
    with open(os.path.join(out, "particle_file_late_garbage.xml"), "w", encoding="utf-8") as f:
        f.write(edited(scene, 'value="tension_block_particles.txt"', 'value="late_garbage_particles.txt"'))
    # Presets: a good one and one that is not XML.
    presets = os.path.join(out, "xml", "solvers")
    os.makedirs(presets, exist_ok=True)
    shutil.copy(os.path.join(src, "..", "xml", "solvers", "direct.xml"), presets)
    with open(os.path.join(presets, "broken.xml"), "w", encoding="utf-8") as f:
        f.write('<ParameterList name="Linear Solver">\n  <Parameter name="Linear Solver Type" type="string" value="Amesos2"\n')


if __name__ == "__main__":
    main()
