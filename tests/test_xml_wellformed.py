"""Every XML file the project ships parses with a strict parser, and the URDF writer keeps comments legal.

urdfdom (TinyXML2) tolerates what XML 1.0 forbids, such as "--" inside a comment (sec. 2.5); Python's
ElementTree (expat) and xmllint do not. A user's tools are strict: the shipped puma560.urdf once had
"--out" in its header comment and failed them. Run by CTest (Python.XmlWellFormed).
"""
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
XML_SUFFIXES = (".urdf", ".xml", ".sdf", ".xacro", ".launch", ".srdf")
SKIP_DIRS = {".git", "build", "__pycache__", "node_modules"}


def shipped_xml_files():
    out = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = [d for d in dirnames if d not in SKIP_DIRS and not d.startswith("build")]
        out += [os.path.join(dirpath, f) for f in filenames if f.endswith(XML_SUFFIXES)]
    return sorted(out)


def test_there_are_xml_files_to_check():
    assert os.path.join(ROOT, "models", "robots", "puma560.urdf") in shipped_xml_files()


@pytest.mark.parametrize("path", shipped_xml_files(), ids=lambda p: os.path.relpath(p, ROOT))
def test_a_shipped_xml_file_is_well_formed(path):
    ET.parse(path)  # raises ParseError naming the line and column


def test_the_urdf_writer_keeps_dashes_out_of_comments(tmp_path):
    # A robot file whose path has "--" in it (and ends a comment line with "-"): the URDF written
    # from it still parses strictly, and pumasim reads the same robot from it.
    src = os.path.join(ROOT, "models", "robots", "planar2.toml")
    folder = tmp_path / "arm--v2-"
    folder.mkdir()
    robot = folder / "planar--2-.toml"
    robot.write_text(open(src).read())
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "robot_to_urdf.py"), str(robot),
                        "--out", str(folder / "out--.urdf")], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    text = (folder / "out--.urdf").read_text()
    comment = text[text.index("<!--") + 4:text.index("-->")]
    assert "--" not in comment and "planar- -2-.toml" in comment
    ET.fromstring(text[text.index("?>") + 2:])
