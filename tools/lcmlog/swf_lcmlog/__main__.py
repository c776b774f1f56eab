"""swf-lcmlog: what an LCM log holds, or every message in it as JSON (python3 -m swf_lcmlog).

Exit codes: 0 the whole log read and decoded; 1 a damaged log or a payload that does not decode
(the message names the record and its byte offset; what was printed before it stands), or a
summary with nothing in it (an empty log, a channel given with --channel that has no messages);
2 a usage error."""
import argparse
import json
import os
import sys

import swf_lcmlog


def summary(path, channels):
    """{channel: {type, messages, bytes, first_utime, last_utime}} over the log."""
    out = {}
    for m in swf_lcmlog.messages(path, channels):
        r = m.record
        c = out.setdefault(r.channel, {'type': m.type_name, 'messages': 0, 'bytes': 0,
                                       'first_utime': r.utime, 'last_utime': r.utime})
        if c['type'] != m.type_name:
            raise swf_lcmlog.LogError('%s: record %d at byte %d: channel %s carries %s after %s' %
                                      (path, r.index, r.offset, r.channel, m.type_name, c['type']))
        c['messages'] += 1
        c['bytes'] += len(r.data)
        c['last_utime'] = r.utime
    return out


def dump(path, channels, out):
    """One JSON object per record: where it is, its channel and type, and its decoded fields
    (null for a type this build does not know)."""
    for m in swf_lcmlog.messages(path, channels):
        r = m.record
        line = {'index': r.index, 'offset': r.offset, 'eventnum': r.eventnum, 'utime': r.utime,
                'channel': r.channel, 'type': m.type_name,
                'fields': None if m.value is None else swf_lcmlog.to_json(m.value)}
        out.write(json.dumps(line, allow_nan=False, separators=(',', ':')) + '\n')


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog='swf-lcmlog', description=__doc__.split('\n\n')[0],
        epilog=__doc__.split('\n\n', 1)[1])
    parser.add_argument('log', help='an LCM log (e.g. out/demo/descent.lcmlog)')
    parser.add_argument('--dump', action='store_true',
                        help='print every message as one JSON object per line instead of the '
                             'per-channel summary')
    parser.add_argument('--channel', action='append', metavar='NAME',
                        help='only this channel (repeatable)')
    parser.add_argument('--version', action='version',
                        version='swf-lcmlog ' + os.environ.get('SWF_VERSION', '(source tree)'))
    args = parser.parse_args(argv)
    channels = set(args.channel) if args.channel else None
    try:
        if args.dump:
            dump(args.log, channels, sys.stdout)
        else:
            found = summary(args.log, channels)
            print(json.dumps(found, indent=2, allow_nan=False))
            # Nothing to read deserves an exit code: a logger that recorded nothing, a channel
            # misspelt.
            missing = sorted(channels - set(found)) if channels else [] if found else ['any channel']
            if missing:
                raise swf_lcmlog.LogError('%s: no messages on %s' % (args.log, ', '.join(missing)))
    except BrokenPipeError:
        # The reader of our output stopped early (`| head`): not an error of the log.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (swf_lcmlog.LogError, OSError) as e:
        sys.stdout.flush()
        print('swf-lcmlog: %s' % e, file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
