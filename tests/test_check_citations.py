"""Tests of scripts/check_citations.py on hand-made comments.

    /usr/bin/python3 -m pytest -q tests/test_check_citations.py
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import check_citations  # noqa: E402


def bad(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return check_citations.main([str(path)])


def test_cpp_comment_citing_outside_or_missing_files_fails(tmp_path, capsys):
    assert bad(tmp_path, "a.cpp", "// Source: ../shared/reference/puma560.md, section 6.\nint x;\n") == 1
    assert "outside the repository" in capsys.readouterr().out
    assert bad(tmp_path, "b.cpp", "/* values: models/robots/no_such_robot.toml */\n") == 1
    assert bad(tmp_path, "c.cpp", "// /work/shared/reference/puma560.md\n") == 1
    assert bad(tmp_path, "d.cpp", "// as in no_such_file.cpp\n") == 1


def test_existing_files_units_urls_and_literals_pass(tmp_path):
    assert bad(tmp_path, "e.cpp",
               "// Source: models/robots/puma560_sources.md; odeint.cpp; 6.1 ms per ohm, 1/s, h/dt;\n"
               "// github.com/petercorke/robotics-toolbox-matlab/models/mdl_puma560.m, https://x.org/a/b.md\n"
               "// build/release/bin/pumasim, runs/paper_slow/stats.json\n"
               "const char* p = \"../shared/reference/puma560.md\";  // a string, not a citation\n") == 0


def test_python_comments_and_docstrings_are_read(tmp_path):
    assert bad(tmp_path, "f.py", '"""See experiments/pumasim_exp/io.py."""\nx = "../shared/x.md"  # fine\n') == 0
    assert bad(tmp_path, "g.py", '"""See ../shared/reference/puma560.md."""\n') == 1
    assert bad(tmp_path, "h.py", "x = 1  # from scripts/no_such_script.py\n") == 1
