"""
The photometry CSV reader cannot be abused (issue 48): each hostile file is one clear line.

A FIFO (with no writer: it must not block), a directory and a character device are refused by
their kind before any read; a file above the byte limit before it is read; more data lines than
the limit at the first one beyond it; a UTF-8 byte-order mark is read; a magnitude of 1e300, an
error of 1e-300, a line with more or fewer fields than the header, bytes that are not UTF-8 each
name their line. Through ``analyze --photometry``: one ``ERROR:`` line, status 1.
"""
import os

import numpy as np
import pytest

from tumble_ros.analysis import photometry_file
from tumble_ros.analysis.photometry_file import (MAX_PHOTOMETRY_BYTES, MAX_PHOTOMETRY_ROWS,
                                                 read_photometry)
from tumble_ros.errors import AnalysisError


def rows(count, start=1):
    """Return ``count`` data lines 'jd,mag,err' half an hour apart."""
    return ''.join(f'{2460000.5 + k / 48:.6f},{15 + 0.1 * np.sin(k):.4f},0.01\n'
                   for k in range(start, start + count))


def test_a_fifo_without_a_writer_is_refused_by_its_kind_at_once(tmp_path, alarm):
    fifo = tmp_path / 'obs.csv'
    os.mkfifo(fifo)
    with pytest.raises(AnalysisError, match=r'obs.csv: is a FIFO \(named pipe\), not a '
                                            r'photometry file \(only regular files are read\)'):
        read_photometry(fifo)


@pytest.mark.parametrize('path, kind', [(None, 'is a directory'),
                                        ('/dev/zero', 'is a character device')])
def test_a_directory_or_a_device_is_refused_by_its_kind(tmp_path, alarm, path, kind):
    with pytest.raises(AnalysisError, match=f'{kind}, not a photometry file \\(only regular '
                                            f'files are read\\)'):
        read_photometry(tmp_path if path is None else path)


def test_a_file_above_the_byte_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    big = tmp_path / 'big.csv'
    with open(big, 'wb') as out:          # sparse: no disk, and nothing may read it
        out.truncate(MAX_PHOTOMETRY_BYTES + 1)

    def refuse(*args, **kwargs):
        raise AssertionError('read')
    monkeypatch.setattr(photometry_file.csv, 'reader', refuse)
    with pytest.raises(AnalysisError, match=f'{MAX_PHOTOMETRY_BYTES + 1:,} bytes, above the '
                                            f'limit of {MAX_PHOTOMETRY_BYTES:,}'):
        read_photometry(big)


def test_more_rows_than_the_limit_are_refused_at_the_first_beyond_it(tmp_path, monkeypatch):
    path = tmp_path / 'many.csv'
    path.write_text('# comment\njd,mag,err\n' + rows(60))
    monkeypatch.setattr(photometry_file, 'MAX_PHOTOMETRY_ROWS', 50)
    with pytest.raises(AnalysisError, match='many.csv line 53: more than 50 data lines'):
        read_photometry(path)
    monkeypatch.setattr(photometry_file, 'MAX_PHOTOMETRY_ROWS', 60)
    assert read_photometry(path).t.size == 60


def test_the_row_limit_holds_a_campaign():
    # a campaign holds ~10^4 points: ten times that is read
    assert MAX_PHOTOMETRY_ROWS >= 10 * 10_000
    assert MAX_PHOTOMETRY_BYTES >= MAX_PHOTOMETRY_ROWS * 60      # 60-character lines


def test_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / 'excel.csv'
    path.write_bytes(('JD,Mag,Err\r\n' + rows(30).replace('\n', '\r\n')).encode('utf-8-sig'))
    assert path.read_bytes()[:3] == b'\xef\xbb\xbf'
    data = read_photometry(path)
    assert data.time_column == 'jd' and data.t.size == 30 and data.sigma is not None


@pytest.mark.parametrize('line, match', [
    ('2460001.5,1e300,0.01', r'line 23: mag = 1e\+300 is not a magnitude \(\|mag\| <= 100\)'),
    ('2460001.5,15.0,1e-300', r'line 23: err = 1e-300 must be in \[1e-06, 100\] mag'),
    ('2460001.5,15.0,0.01,7', 'line 23: 4 fields, the header has 3'),
    ('2460001.5,15.0', 'line 23: 2 fields, the header has 3'),
    ('2460001.5,15.0,nan', 'line 23: err = nan must be finite'),
    ('2460001.5,"15,0",0.01', "line 23: mag = '15,0' is not a number"),
])
def test_a_bad_line_is_refused_with_its_number(tmp_path, line, match):
    path = tmp_path / 'bad.csv'
    path.write_text('# a comment\njd,mag,err\n' + rows(20) + line + '\n' + rows(5, 30))
    with pytest.raises(AnalysisError, match=match):
        read_photometry(path)


def test_bytes_that_are_not_utf8_are_refused(tmp_path):
    path = tmp_path / 'latin.csv'
    path.write_bytes(b'jd,mag,err\n' + rows(25).encode() + b'2460001.5,15\xe9,0.01\n')
    with pytest.raises(AnalysisError, match='latin.csv: cannot read it as text: line 27 is not '
                                            'UTF-8'):
        read_photometry(path)


@pytest.mark.parametrize('make, match', [
    (lambda d: os.mkfifo(d / 'obs.csv'), 'is a FIFO'),
    (lambda d: (d / 'obs.csv').write_text('jd,mag\n' + '2460000.5,1e300\n' * 30),
     'is not a magnitude'),
])
def test_analyze_refuses_a_hostile_csv_in_one_line(tmp_path, capsys, alarm, make, match):
    from tumble_ros.analysis.cli import command
    make(tmp_path)
    assert command(['--photometry', str(tmp_path / 'obs.csv')]) == 1
    err = capsys.readouterr().err
    assert err.startswith('ERROR: ') and err.count('\n') == 1 and match in err, err
