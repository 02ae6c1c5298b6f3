"""What the command-line tests check of every refusal: one ``ERROR:`` line, no traceback."""


def one_error_line(capsys) -> str:
    """Return the single ``ERROR: ...`` line on stderr (nothing on stdout, no traceback)."""
    out, err = capsys.readouterr()
    assert out == ''
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith('ERROR: ') and 'Traceback' not in err
    return lines[0]
