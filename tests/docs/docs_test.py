#!/usr/bin/python3
"""Docs that run: the commands of every Markdown document (README.md, docs/*.md, the module
READMEs), extracted and run or checked from the repository root, the directory they are
written for.

usage: docs_test.py BIN_DIR [--list]   (BIN_DIR: the release build's bin/, whose programs the
                                        docs call as build/<preset>/bin/NAME)

Every fenced block must say what it is: ```sh for commands, ```text (or a language) for
anything else; an unlabelled fence fails. Every ```sh block carries, on the line before it, how
this test treats it:

  <!-- docs-test: run -->            run as written (bash -euo pipefail, repository root, 120 s);
                                     fails on a non-zero exit
  <!-- docs-test: check -->          too long, or needs hardware or a display: every command's
                                     program is checked to exist as written (a built program
                                     under build/<preset>/bin, a tracked script, a tools/run verb,
                                     or a program on PATH)
  <!-- docs-test: skip REASON -->    neither (e.g. it edits the tree to show the build refuse it)

And in every document, prose included: a build directory named build/NAME must be one a preset
makes (CMakePresets.json), a command in an sh block must not call an swf-* program by its bare
name (the build does not put them on PATH), and no sh block may write into docs/ (tracked).

Commands inline in prose (`build/release/bin/swf-eval euroc DIR --loop-seconds S`, `swf-sim
--out DIR`, `tools/run eval`) are checked too: the program must be one the build makes (or a
tools/run verb), and every --option must be one its --help (or its subcommand's) lists; a
stale one is named with its file and line."""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ANNOTATION = re.compile(r'<!--\s*docs-test:\s*(run|check|skip)\b\s*(.*?)\s*-->')
FENCE = re.compile(r'^\s*```+\s*([^\s`]*)')
BUILD_DIR = re.compile(r'(?<![\w/.-])build/([A-Za-z0-9_.-]+)')
# Words that wrap a command (the program is the next word) or belong to the shell's grammar.
WRAPPERS = {'taskset', 'sudo', 'time', 'env', 'exec', 'nice'}
KEYWORDS = {'for', 'do', 'done', 'if', 'then', 'else', 'fi', 'while', 'in', '{', '}', '(', ')'}
RUN_TIMEOUT_S = 120


def documents():
    listed = subprocess.run(['git', 'ls-files', '*.md'], cwd=ROOT, stdout=subprocess.PIPE,
                            text=True, check=True).stdout.split()
    return sorted(listed)


def preset_build_dirs():
    with open(os.path.join(ROOT, 'CMakePresets.json')) as f:
        presets = json.load(f)['configurePresets']
    return {p['name'] for p in presets if not p.get('hidden')}


def blocks(path, errors):
    """(first line number, info string, annotation (kind, reason) or None, text) of every
    fenced block."""
    with open(os.path.join(ROOT, path)) as f:
        lines = f.read().split('\n')
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, info = i, m.group(1)
        j = i + 1
        while j < len(lines) and not FENCE.match(lines[j]):
            j += 1
        if j == len(lines):
            errors.append('%s:%d: unterminated code block' % (path, start + 1))
        previous = next((lines[k] for k in range(start - 1, -1, -1) if lines[k].strip()), '')
        a = ANNOTATION.search(previous)
        out.append((start + 1, info, (a.group(1), a.group(2)) if a else None,
                    '\n'.join(lines[start + 1:j])))
        i = j + 1
    return out


def commands(script):
    """The simple commands of a shell script: continuation lines joined, comments dropped,
    split at ; && || | and newlines (quoted text kept whole: it is one argument)."""
    lexer = shlex.shlex(script.replace('\\\n', ' '), posix=True, punctuation_chars=';&|()')
    lexer.whitespace = ' \t\r'
    lexer.commenters = '#'
    out, current = [], []
    for token in lexer:
        if token == '\n' or set(token) <= set(';&|()'):
            if current:
                out.append(current)
            current = []
        else:
            current.append(token)
    if current:
        out.append(current)
    return out


def program_of(words):
    """The program a simple command runs: after variable assignments, wrappers and their
    options (taskset -c 1 X), and shell keywords; None for a bare assignment or keyword."""
    if words[0] in ('for', 'case', 'select'):  # `for VAR in WORDS`: no program
        return None, []
    k = 0
    while k < len(words):
        w = words[k]
        if re.match(r'^[A-Za-z_][A-Za-z0-9_]*=', w) or w in KEYWORDS:
            k += 1
        elif w in WRAPPERS:
            k += 1
            while k < len(words) and words[k].startswith('-'):
                k += 2 if w == 'taskset' else 1
        else:
            return w, words[k + 1:]
    return None, []


def tools_run_verbs():
    with open(os.path.join(ROOT, 'tools/run')) as f:
        text = f.read()
    return set(re.findall(r'^  ([a-z]+)\)$', text, re.M))


def check_program(program, args, bin_dir, verbs):
    """Why `program` does not run as written from the repository root, or None."""
    if program.startswith('swf-'):
        return '%s is not on PATH: write build/release/bin/%s' % (program, program)
    m = re.match(r'^build/([^/]+)/bin/(.+)$', program)
    if m:
        if not os.access(os.path.join(bin_dir, m.group(2)), os.X_OK):
            return '%s: the build makes no program %s' % (program, m.group(2))
        return None
    if program == 'tools/run':
        verb = args[0] if args else 'help'
        return None if verb in verbs | {'help'} else 'tools/run has no verb %r' % verb
    if '/' in program:
        path = os.path.join(ROOT, program)
        return None if os.access(path, os.X_OK) else '%s: no such executable' % program
    if program.startswith('$'):
        return None
    return None if shutil.which(program) else '%s: not installed (not on PATH)' % program


INLINE_CODE = re.compile(r'(?<!`)`([^`\n]+)`(?!`)')
INLINE_PROGRAM = re.compile(r'^(?:build/[^/\s]+/bin/)?(swf-[a-z-]+)$')


def inline_commands(path):
    """(line number, words) of every code span in prose (outside fenced blocks) that starts with
    an swf-* program or tools/run."""
    out, fenced = [], False
    with open(os.path.join(ROOT, path)) as f:
        for n, line in enumerate(f, 1):
            if FENCE.match(line):
                fenced = not fenced
                continue
            if fenced:
                continue
            for span in INLINE_CODE.findall(line):
                try:
                    words = shlex.split(span)
                except ValueError:
                    words = span.split()
                if words and (INLINE_PROGRAM.match(words[0]) or words[0] == 'tools/run'):
                    out.append((n, words))
    return out


class HelpTexts:
    """What each program (and subcommand) says it accepts: its --help output, run once."""

    def __init__(self, bin_dir):
        self.bin_dir, self.cache = bin_dir, {}

    def text(self, program, *sub):
        key = (program,) + sub
        if key not in self.cache:
            path = os.path.join(self.bin_dir, program)
            try:
                r = subprocess.run([path] + list(sub) + ['--help'], stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, timeout=20)
                self.cache[key] = r.stdout if r.returncode == 0 else ''
            except (OSError, subprocess.TimeoutExpired):
                self.cache[key] = ''
        return self.cache[key]


def check_inline(words, bin_dir, verbs, helps):
    """Why an inline command is stale, or None."""
    if words[0] == 'tools/run':
        verb = words[1] if len(words) > 1 else 'help'
        return None if verb in verbs | {'help'} or verb.startswith('-') else \
            'tools/run has no verb %r' % verb
    program = INLINE_PROGRAM.match(words[0]).group(1)
    if not os.access(os.path.join(bin_dir, program), os.X_OK):
        return 'the build makes no program %s' % program
    texts = [helps.text(program)]
    if len(words) > 1 and re.match(r'^[a-z][a-z-]*$', words[1]):
        texts.append(helps.text(program, words[1]))  # a subcommand's own options
    for w in words[1:]:
        w = w.lstrip('[(').split('=', 1)[0].rstrip('])|.,;:')  # [--set KEY]... names --set
        if not w.startswith('--') or w == '--':
            continue
        option = w
        if not any(re.search(r'(?<![\w-])%s(?![\w-])' % re.escape(option), t) for t in texts):
            return '%s does not accept %s (not in its --help)' % (program, option)
    return None


def writes_into_docs(words):
    return any(w.startswith('docs/') or w.startswith('./docs/') for w in words)


def main():
    bin_dir = os.path.abspath(sys.argv[1])
    list_only = '--list' in sys.argv[2:]
    presets = preset_build_dirs()
    verbs = tools_run_verbs()
    helps = HelpTexts(bin_dir)
    errors, ran, checked, skipped = [], [], [], []
    inline = 0
    for path in documents():
        for n, words in inline_commands(path):
            inline += 1
            problem = check_inline(words, bin_dir, verbs, helps)
            if problem:
                errors.append('%s:%d: inline `%s`: %s' % (path, n, ' '.join(words), problem))
        with open(os.path.join(ROOT, path)) as f:
            for n, line in enumerate(f, 1):
                for name in BUILD_DIR.findall(line):
                    if name not in presets and not name.startswith('<'):
                        errors.append('%s:%d: build/%s: no preset makes it (presets: %s)' %
                                      (path, n, name, ', '.join(sorted(presets))))
        for line, info, annotation, text in blocks(path, errors):
            where = '%s:%d' % (path, line)
            if not info:
                errors.append('%s: unlabelled code block (```sh for commands, ```text else)' %
                              where)
                continue
            if info != 'sh':
                continue
            if annotation is None:
                errors.append('%s: sh block without <!-- docs-test: run|check|skip REASON -->' %
                              where)
                continue
            kind, reason = annotation
            cmds = commands(text)
            for words in cmds:
                program, args = program_of(words)
                if program and program.startswith('swf-'):
                    errors.append('%s: %s' % (where, check_program(program, args, bin_dir,
                                                                   verbs)))
                if writes_into_docs(words):
                    errors.append('%s: writes into the tracked docs/: %s' %
                                  (where, ' '.join(words)))
            if kind == 'skip':
                if not reason:
                    errors.append('%s: docs-test: skip needs a reason' % where)
                skipped.append('%s (%s)' % (where, reason))
            elif kind == 'check':
                for words in cmds:
                    program, args = program_of(words)
                    if not program or program.startswith('swf-'):  # reported above
                        continue
                    problem = check_program(program, args, bin_dir, verbs)
                    if problem:
                        errors.append('%s: %s' % (where, problem))
                checked.append(where)
            elif list_only:
                ran.append(where)
            else:
                print('== run %s' % where, flush=True)
                try:
                    result = subprocess.run(['bash', '-euo', 'pipefail', '-c', text], cwd=ROOT,
                                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                            text=True, timeout=RUN_TIMEOUT_S)
                    if result.returncode != 0:
                        errors.append('%s: exit %d:\n%s' % (where, result.returncode,
                                                            result.stdout[-3000:]))
                except subprocess.TimeoutExpired:
                    errors.append('%s: still running after %d s' % (where, RUN_TIMEOUT_S))
                ran.append(where)
    print('run (%d): %s' % (len(ran), ', '.join(ran)))
    print('checked (%d): %s' % (len(checked), ', '.join(checked)))
    print('skipped (%d): %s' % (len(skipped), '; '.join(skipped)))
    print('inline commands checked: %d' % inline)
    for e in errors:
        print('FAIL: ' + e)
    if not ran:
        print('FAIL: no block ran')
        return 1
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
