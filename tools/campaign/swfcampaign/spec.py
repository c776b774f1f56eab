"""The campaign spec: a YAML file naming the nominal swf-sil configuration, fixed overrides and the
dispersions, validated with `file:line: field: problem` errors.

    name: default                      # a word: [A-Za-z0-9_-]+
    seed: 20261127                     # campaign seed (integer >= 0)
    runs: 24                           # number of runs (1 .. 100000)
    config: ../../../fsw/app/config/demo.cfg   # relative to the spec file
    keep_worst: 3                      # worst runs whose LCM log the report keeps (default 3)
    timeout_s: 900                     # a run still flying after this is killed (default 1800)
    fixed:                             # --set overrides of every run
      sim.frames: 60
    dispersions:                       # --set overrides drawn per run
      sim.start_altitude_m: {normal: [100, 5], min: 80, max: 120}
      sim.sun_azimuth_deg: {uniform: [0, 360]}
      sim.attitude_deg: {normal: [[0, 0, 0], [1, 1, 2]]}   # vectors: element-wise
      sim.terrain: {choice: [rocks, craters], weights: [3, 1]}
      sim.seed: run_seed               # the run's own seed

Every run draws from its own generator, seeded by SHA-256 of (campaign seed, run index), in the
order of the dispersion keys as sorted: a run's overrides do not depend on how many runs there are
or in which order they fly, so any run is reproducible alone.
"""
import hashlib
import math
import os
import random
import re

import yaml

TOP_KEYS = {'name', 'seed', 'runs', 'config', 'keep_worst', 'timeout_s', 'fixed', 'dispersions'}
KINDS = ('normal', 'uniform', 'choice')
CONFIG_KEY = re.compile(r'^[a-z][a-z0-9_]*(\.[a-z][a-z0-9_]*)*$')
RUN_SEED = 'run_seed'
# Keys the campaign sets itself on every run.
RESERVED = {'pacing', 'lcm.publish', 'rt.mlockall', 'rt.priority', 'summary.path', 'record.path',
            'summary.plot_dir', 'source', 'log.path'}


class SpecError(Exception):
    """A spec problem, already formatted as `file:line: field: problem`."""


class Spec:
    def __init__(self):
        self.path = ''
        self.text = ''
        self.name = ''
        self.seed = 0
        self.runs = 0
        self.config = ''
        self.keep_worst = 3
        self.timeout_s = 1800.0
        self.fixed = {}          # key -> value text
        self.dispersions = {}    # key -> Dispersion
        self.lines = {}          # field -> line of the spec (for errors found later)

    def digest(self):
        """What identifies the campaign's runs: the spec text (but its number of runs) and the
        nominal config's text."""
        h = hashlib.sha256(re.sub(r'(?m)^runs:.*$', 'runs:', self.text).encode())
        with open(self.config, 'rb') as f:
            h.update(f.read())
        return h.hexdigest()


class Dispersion:
    def __init__(self, kind, params, lo=None, hi=None, weights=None):
        self.kind = kind        # normal | uniform | choice | run_seed
        self.params = params    # normal: (mean, sigma) lists; uniform: (lo, hi) lists; choice
        self.lo = lo
        self.hi = hi
        self.weights = weights

    def draw(self, rng, run_seed):
        if self.kind == RUN_SEED:
            return str(run_seed)
        if self.kind == 'choice':
            return format_value(rng.choices(self.params, weights=self.weights)[0])
        a, b = self.params
        if self.kind == 'normal':
            values = [rng.gauss(m, s) for m, s in zip(a, b)]
        else:
            values = [rng.uniform(lo, hi) for lo, hi in zip(a, b)]
        values = [min(max(v, self.lo if self.lo is not None else v),
                      self.hi if self.hi is not None else v) for v in values]
        return ', '.join(format_value(v) for v in values)

    def extremes(self):
        """Values a run may take at the edges of the distribution (checked against swf-sil)."""
        if self.kind == RUN_SEED:
            return ['1']
        if self.kind == 'choice':
            return [format_value(p) for p in self.params]
        a, b = self.params
        if self.kind == 'uniform':
            return [', '.join(format_value(v) for v in a), ', '.join(format_value(v) for v in b)]
        if self.lo is None and self.hi is None:
            return [', '.join(format_value(v) for v in a)]
        ends = []
        for bound in (self.lo, self.hi):
            if bound is not None:
                ends.append(', '.join(format_value(bound) for _ in a))
        return ends


def format_value(v):
    if isinstance(v, bool):
        return 'true' if v else 'false'
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def run_seed(campaign_seed, index):
    """The run's seed: the first 8 bytes of SHA-256("campaign_seed:index"), as an integer."""
    digest = hashlib.sha256(('%d:%d' % (campaign_seed, index)).encode()).digest()
    return int.from_bytes(digest[:8], 'big') & 0x7FFFFFFF


def overrides(spec, index):
    """The run's --set overrides (key -> value text): fixed ones, then the drawn dispersions."""
    seed = run_seed(spec.seed, index)
    rng = random.Random(seed)
    out = dict(spec.fixed)
    for key in sorted(spec.dispersions):
        out[key] = spec.dispersions[key].draw(rng, seed)
    return out


def _error(spec_path, node, field, problem):
    line = node.start_mark.line + 1 if node is not None else 1
    return SpecError('%s:%d: %s: %s' % (spec_path, line, field, problem))


def _scalar(node):
    """The Python value of a scalar node (YAML's own typing), or None for a non-scalar."""
    if not isinstance(node, yaml.ScalarNode):
        return None
    return yaml.safe_load(yaml.serialize(node))


def _number(path, node, field):
    v = _scalar(node)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _error(path, node, field, 'expected a finite number, got %r' % (v if v is not None
                                                                              else node.tag))
    return float(v)


def _vector(path, node, field):
    """A number or a list of numbers, as a list."""
    if isinstance(node, yaml.SequenceNode):
        if not node.value:
            raise _error(path, node, field, 'an empty list')
        return [_number(path, n, field) for n in node.value]
    return [_number(path, node, field)]


def _integer(path, node, field, lo, hi):
    v = _scalar(node)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise _error(path, node, field, 'expected an integer in [%d, %d], got %r' % (lo, hi, v))
    return v


def _config_value(path, node, field):
    v = _scalar(node)
    if isinstance(node, yaml.SequenceNode):
        return ', '.join(format_value(_scalar(n)) for n in node.value)
    if v is None:
        raise _error(path, node, field, 'expected a value')
    if isinstance(v, float) and not math.isfinite(v):
        raise _error(path, node, field, 'not a finite number')
    return format_value(v)


def _dispersion(path, key, node):
    field = 'dispersions.' + key
    if isinstance(node, yaml.ScalarNode):
        if _scalar(node) == RUN_SEED:
            return Dispersion(RUN_SEED, None)
        raise _error(path, node, field, 'expected run_seed or a mapping with one of %s'
                     % ', '.join(KINDS))
    if not isinstance(node, yaml.MappingNode):
        raise _error(path, node, field, 'expected a mapping with one of %s' % ', '.join(KINDS))
    entries = {k.value: (k, v) for k, v in node.value}
    kinds = [k for k in KINDS if k in entries]
    if len(kinds) != 1:
        raise _error(path, node, field, 'give exactly one of %s' % ', '.join(KINDS))
    kind = kinds[0]
    allowed = {kind, 'min', 'max'} | ({'weights'} if kind == 'choice' else set())
    for name, (knode, _) in entries.items():
        if name not in allowed:
            raise _error(path, knode, field + '.' + name, 'unknown field (allowed: %s)'
                         % ', '.join(sorted(allowed)))
    vnode = entries[kind][1]
    if kind == 'choice':
        if not isinstance(vnode, yaml.SequenceNode) or not vnode.value:
            raise _error(path, vnode, field + '.choice', 'expected a non-empty list')
        params = [_scalar(n) for n in vnode.value]
        if any(p is None for p in params):
            raise _error(path, vnode, field + '.choice', 'choices must be plain values')
        weights = None
        if 'weights' in entries:
            wnode = entries['weights'][1]
            weights = _vector(path, wnode, field + '.weights')
            if len(weights) != len(params) or min(weights) < 0 or sum(weights) <= 0:
                raise _error(path, wnode, field + '.weights',
                             'one non-negative weight per choice, not all zero')
        return Dispersion('choice', params, weights=weights)
    if not isinstance(vnode, yaml.SequenceNode) or len(vnode.value) != 2:
        raise _error(path, vnode, field + '.' + kind, 'expected [%s]'
                     % ('mean, sigma' if kind == 'normal' else 'low, high'))
    a = _vector(path, vnode.value[0], field + '.' + kind)
    b = _vector(path, vnode.value[1], field + '.' + kind)
    if len(a) != len(b):
        raise _error(path, vnode, field + '.' + kind, 'the two vectors differ in length')
    if kind == 'normal' and min(b) < 0:
        raise _error(path, vnode, field + '.normal', 'a negative sigma')
    if kind == 'uniform' and any(lo > hi for lo, hi in zip(a, b)):
        raise _error(path, vnode, field + '.uniform', 'low above high')
    lo = _number(path, entries['min'][1], field + '.min') if 'min' in entries else None
    hi = _number(path, entries['max'][1], field + '.max') if 'max' in entries else None
    if lo is not None and hi is not None and lo > hi:
        raise _error(path, entries['min'][1], field + '.min', 'min above max')
    return Dispersion(kind, (a, b), lo, hi)


def load(spec_path, config=None):
    """Reads and validates a spec; raises SpecError. The config keys themselves are checked by
    swf-sil (engine.check_against_sil). `config` replaces the nominal config the spec names (a
    campaign directory's own copy)."""
    try:
        with open(spec_path, encoding='utf-8') as f:
            text = f.read()
    except OSError as e:
        raise SpecError('%s: cannot read: %s' % (spec_path, e.strerror)) from None
    except UnicodeDecodeError:
        raise SpecError('%s: not UTF-8 text' % spec_path) from None
    try:
        root = yaml.compose(text)
    except yaml.YAMLError as e:
        mark = getattr(e, 'problem_mark', None)
        line = mark.line + 1 if mark is not None else 1
        raise SpecError('%s:%d: (syntax): %s' % (spec_path, line,
                                                 getattr(e, 'problem', None) or e)) from None
    if not isinstance(root, yaml.MappingNode):
        raise _error(spec_path, root, '(top)', 'expected a mapping of fields')
    spec = Spec()
    spec.path = spec_path
    spec.text = text
    fields = {}
    for knode, vnode in root.value:
        key = _scalar(knode)
        if key not in TOP_KEYS:
            raise _error(spec_path, knode, str(key), 'unknown field (allowed: %s)'
                         % ', '.join(sorted(TOP_KEYS)))
        if key in fields:
            raise _error(spec_path, knode, key, 'given twice')
        fields[key] = vnode
        spec.lines[key] = knode.start_mark.line + 1
    for required in ('name', 'seed', 'runs', 'config'):
        if required not in fields:
            raise _error(spec_path, root, required, 'missing')
    name = _scalar(fields['name'])
    if not isinstance(name, str) or not re.fullmatch(r'[A-Za-z0-9_-]+', name):
        raise _error(spec_path, fields['name'], 'name', 'expected a word of [A-Za-z0-9_-]')
    spec.name = name
    spec.seed = _integer(spec_path, fields['seed'], 'seed', 0, 2**63 - 1)
    spec.runs = _integer(spec_path, fields['runs'], 'runs', 1, 100000)
    if 'keep_worst' in fields:
        spec.keep_worst = _integer(spec_path, fields['keep_worst'], 'keep_worst', 0, 1000)
    if 'timeout_s' in fields:
        spec.timeout_s = _number(spec_path, fields['timeout_s'], 'timeout_s')
        if spec.timeout_s <= 0:
            raise _error(spec_path, fields['timeout_s'], 'timeout_s', 'must be positive')
    named = _scalar(fields['config'])
    if not isinstance(named, str) or not named:
        raise _error(spec_path, fields['config'], 'config', 'expected a path')
    spec.config = config or os.path.normpath(
        os.path.join(os.path.dirname(os.path.abspath(spec_path)), named))
    if not os.path.isfile(spec.config):
        raise _error(spec_path, fields['config'], 'config', 'no such file: %s' % spec.config)
    for section in ('fixed', 'dispersions'):
        node = fields.get(section)
        if node is None:
            continue
        if not isinstance(node, yaml.MappingNode):
            raise _error(spec_path, node, section, 'expected a mapping of config keys')
        for knode, vnode in node.value:
            key = _scalar(knode)
            field = '%s.%s' % (section, key)
            if not isinstance(key, str) or not CONFIG_KEY.match(key):
                raise _error(spec_path, knode, field, 'not a swf-sil config key')
            if key in RESERVED:
                raise _error(spec_path, knode, field, 'set by the campaign itself')
            if key in spec.fixed or key in spec.dispersions:
                raise _error(spec_path, knode, field, 'given twice')
            spec.lines[key] = knode.start_mark.line + 1
            if section == 'fixed':
                spec.fixed[key] = _config_value(spec_path, vnode, field)
            else:
                spec.dispersions[key] = _dispersion(spec_path, key, vnode)
    return spec
