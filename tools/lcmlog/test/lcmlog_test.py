#!/usr/bin/python3
"""swf_lcmlog against C++ on a real recording, and on damaged copies of it.

usage: lcmlog_test.py SWF-SIL LCMLOG-DUMP SWF-LCMLOG CONFIG   (PYTHONPATH: build/<preset>/python)

GIVEN a 5-frame demo descent recorded by swf-sil (every channel the flight process and the
simulator write), WHEN swf_lcmlog decodes it and lcmlog_dump (LCM's own log reader and the C++
types) prints it, THEN both hold the same records in the same order, every record decodes to a
known type, and every field has the same value, exactly: same JSON type (bool, int, float,
string, list) and same number (floats as their shortest round-trip decimal, so equal bits).
Then the damaged copies: each gives an error naming the record and its byte offset, and the
command-line tool exits 1 with it."""
import json
import os
import struct
import subprocess
import sys
import tempfile
import unittest

import numpy
import swf_lcmlog

SIL, DUMP, CLI, CONFIG = sys.argv[1:5]
# Every channel a recorded demo carries (fsw/app, tools/sil): a missing one fails the test, so
# that a channel added later is either decoded or noticed here.
CHANNELS = {'SWF_STEREO', 'SWF_NAV', 'SWF_FEATURES', 'SWF_LANDMARKS', 'SWF_HAZARD', 'SWF_HEALTH',
            'SWF_IMU', 'SIM_TRUTH', 'SIM_TRUTH_LANDMARKS', 'SIM_TRUTH_HAZARD'}


def same(a, b, where):
    """None when a and b are the same JSON value, type included; else where they differ."""
    if type(a) is not type(b):
        return '%s: %r (%s) vs %r (%s)' % (where, a, type(a).__name__, b, type(b).__name__)
    if isinstance(a, dict):
        if list(a) != list(b):
            return '%s: fields %s vs %s' % (where, list(a), list(b))
        for k in a:
            d = same(a[k], b[k], '%s.%s' % (where, k))
            if d:
                return d
        return None
    if isinstance(a, list):
        if len(a) != len(b):
            return '%s: %d vs %d elements' % (where, len(a), len(b))
        for i, (x, y) in enumerate(zip(a, b)):
            d = same(x, y, '%s[%d]' % (where, i))
            if d:
                return d
        return None
    return None if a == b else '%s: %r vs %r' % (where, a, b)


class LcmlogTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.log = os.path.join(cls.dir.name, 'demo.lcmlog')
        subprocess.run([SIL, '--config', CONFIG, '--set', 'sim.frames: 5',
                        '--set', 'pacing: lockstep', '--set', 'lcm.publish: false',
                        '--set', 'rt.mlockall: false', '--set', 'rt.priority: 0',
                        '--set', 'record.path: ' + cls.log,
                        '--set', 'summary.path: ' + os.path.join(cls.dir.name, 'summary.json')],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(cls.log, 'rb') as f:
            cls.bytes = f.read()

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def write(self, name, data):
        path = os.path.join(self.dir.name, name)
        with open(path, 'wb') as f:
            f.write(data)
        return path

    def test_every_record_of_every_channel_matches_cpp(self):
        dump = subprocess.run([DUMP, self.log], check=True, stdout=subprocess.PIPE, text=True)
        cpp = [json.loads(line) for line in dump.stdout.splitlines()]
        python = list(swf_lcmlog.messages(self.log))
        self.assertEqual(len(python), len(cpp))
        seen = {}
        for p, c in zip(python, cpp):
            r = p.record
            where = 'record %d (%s)' % (r.index, r.channel)
            self.assertEqual((r.index, r.eventnum, r.utime, r.channel, p.type_name),
                             (c['index'], c['eventnum'], c['utime'], c['channel'], c['type']),
                             where)
            self.assertIsNotNone(p.value, where + ': not decoded')
            # Both sides through JSON text, so that both meet the same number parser.
            fields = json.loads(json.dumps(swf_lcmlog.to_json(p.value), allow_nan=False))
            self.assertIsNone(same(fields, c['fields'], where))
            seen[r.channel] = seen.get(r.channel, 0) + 1
        self.assertEqual(set(seen), CHANNELS)
        self.assertEqual(seen['SWF_STEREO'], 5)
        self.assertEqual(seen['SWF_NAV'], 5)
        print('python and C++ agree on %d records: %s' % (len(python), json.dumps(seen)))

    def test_table_stacks_a_channel_into_arrays(self):
        nav = swf_lcmlog.table(self.log, 'SWF_NAV')
        self.assertEqual(nav['position_world_m'].shape, (5, 3))
        self.assertEqual(nav['covariance'].shape, (5, 36))
        numpy.testing.assert_array_equal(nav['frame_seq'], numpy.arange(5) + nav['frame_seq'][0])
        stereo = swf_lcmlog.table(self.log, 'SWF_STEREO')
        w, h = int(stereo['width'][0]), int(stereo['height'][0])
        self.assertEqual(stereo['left'].shape, (5, w * h))
        self.assertEqual(stereo['left'].dtype, numpy.uint8)
        hazard = swf_lcmlog.table(self.log, 'SWF_HAZARD')
        self.assertEqual(hazard['elevation_m'].shape[1], int(hazard['num_cells'][0]))

    def test_summary_lists_every_channel(self):
        out = subprocess.run([CLI, self.log], check=True, stdout=subprocess.PIPE, text=True)
        summary = json.loads(out.stdout)
        self.assertEqual(set(summary), CHANNELS)
        self.assertEqual(summary['SWF_HAZARD']['type'], 'hazard_map_t')
        self.assertEqual(summary['SWF_STEREO']['messages'], 5)

    def records(self):
        return list(swf_lcmlog.records(self.log))

    def assert_refused(self, data, *expected):
        path = self.write('damaged.lcmlog', data)
        with self.assertRaises(swf_lcmlog.LogError) as caught:
            list(swf_lcmlog.messages(path))
        for text in expected:
            self.assertIn(text, str(caught.exception))
        cli = subprocess.run([CLI, path], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
        self.assertEqual(cli.returncode, 1, cli.stderr)
        self.assertIn(str(caught.exception), cli.stderr)

    def test_truncated_payload_names_record_and_offset(self):
        last = self.records()[-1]
        self.assert_refused(self.bytes[:-3], 'record %d at byte %d' % (last.index, last.offset),
                            'truncated')

    def test_truncated_header_names_record_and_offset(self):
        last = self.records()[-1]
        self.assert_refused(self.bytes[:last.offset + 10],
                            'record %d at byte %d' % (last.index, last.offset),
                            'truncated header')

    def test_wrong_sync_word_names_record_and_offset(self):
        r = self.records()[3]
        damaged = bytearray(self.bytes)
        damaged[r.offset] ^= 0xFF
        self.assert_refused(bytes(damaged), 'record 3 at byte %d' % r.offset, 'sync word')

    def test_negative_array_length_in_a_payload(self):
        # stereo_frame_t.num_bytes: after the fingerprint, four int64, an int32, two booleans,
        # six doubles, width and height.
        r = next(r for r in self.records() if r.channel == 'SWF_STEREO')
        at = r.offset + swf_lcmlog.HEADER.size + len(r.channel) + 8 + 4 * 8 + 4 + 2 + 6 * 8 + 8
        damaged = bytearray(self.bytes)
        damaged[at:at + 4] = struct.pack('>i', -1)
        self.assert_refused(bytes(damaged), 'record %d at byte %d' % (r.index, r.offset),
                            'negative array length')

    def test_payload_with_trailing_bytes(self):
        r = next(r for r in self.records() if r.channel == 'SWF_NAV')
        longer = r.data + b'\0\0'
        header = swf_lcmlog.HEADER.pack(swf_lcmlog.SYNC_WORD, r.eventnum, r.utime,
                                        len(r.channel), len(longer))
        self.assert_refused(header + r.channel.encode() + longer, 'record 0 at byte 0',
                            '2 bytes after the end of the nav_state_t message')

    def test_unknown_type_is_kept_undecoded(self):
        header = swf_lcmlog.HEADER.pack(swf_lcmlog.SYNC_WORD, 0, 1, 5, 12)
        path = self.write('other.lcmlog', header + b'OTHER' + b'\1' * 12)
        (m,) = list(swf_lcmlog.messages(path))
        self.assertEqual((m.record.channel, m.type_name, m.value), ('OTHER', None, None))


if __name__ == '__main__':
    unittest.main(argv=sys.argv[:1], verbosity=2)
