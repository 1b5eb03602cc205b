"""key=value parameters and yade-batch tables read the same keys; bad input names the key."""
import os

import pytest
from woven.params import read_params

DEFAULTS = {'V': (200.0, 'm/s', ''), 'elements': (100, '', ''), 'shape': ('box', '', ''), 'flag': (False, '', '')}


def test_defaults_and_command_line(monkeypatch):
    monkeypatch.delenv('YADE_BATCH', raising=False)
    p = read_params(DEFAULTS, [])
    assert (p.V, p.elements, p.shape, p.flag) == (200.0, 100, 'box', False)
    p = read_params(DEFAULTS, ['V=300', 'elements=2e3', "shape='sphere'", 'flag=1'])
    assert (p.V, p.elements, p.shape, p.flag) == (300.0, 2000, 'sphere', True)
    assert isinstance(p.elements, int) and p.units['V'] == 'm/s'


@pytest.mark.parametrize('arg, key', [('foo=1', 'foo'), ('V=fast', 'V'), ('elements=2.5', 'elements'),
                                      ('flag=maybe', 'flag'), ('V', 'V')])
def test_bad_arguments_name_the_key(monkeypatch, arg, key):
    monkeypatch.delenv('YADE_BATCH', raising=False)
    with pytest.raises(ValueError) as e:
        read_params(DEFAULTS, [arg])
    assert key in str(e.value) and 'allowed' in str(e.value)


def test_yade_batch_table_line(tmp_path, monkeypatch, yade_ns):
    table = tmp_path / 'p.table'
    table.write_text('description V elements shape\nfirst 111 10 sphere\nsecond 222 20 box\n')
    monkeypatch.setenv('YADE_BATCH', '%s:3' % table)  # line 3 of the file = 'second'
    p = read_params(DEFAULTS, [])
    assert (p.V, p.elements, p.shape) == (222.0, 20, 'box')
    p = read_params(DEFAULTS, ['V=5'])  # the command line wins over the table
    assert p.V == 5.0
    table.write_text('description bogus\nx 1\n')
    monkeypatch.setenv('YADE_BATCH', '%s:2' % table)
    with pytest.raises(ValueError, match='bogus'):
        read_params(DEFAULTS, [])
