#!/usr/bin/env python3
"""The rules of tests/docs/examples.py, each shown to refuse what it must and to pass what it
should, on small pages of its own (unit test docs_self; the standard library only)."""
import importlib.util
import os
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location('examples', os.path.join(HERE, 'examples.py'))
ex = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ex)

F = '```'


def page(*lines):
    return '\n'.join(lines) + '\n'


def blocks(text):
    return ex.parse('page.md', text)


def refused(script, lang='sh'):
    return ex.lcm_problems(ex.Block('page.md', 1, lang, script, None))


class Fences(unittest.TestCase):
    def test_shell_blocks_and_markers(self):
        b, p = blocks(page(F + 'sh', 'mvod --help', F, '',
                           '<!-- not run: camera: needs /dev/video0 -->', F + 'console',
                           '$ mvod --list-cameras', F, F + 'ini', '[vo]', F))
        self.assertEqual(p, [])
        self.assertEqual([x.lang for x in b], ['sh', 'console'])
        self.assertIsNone(b[0].marker)
        self.assertEqual(b[1].marker.group(1), 'camera')

    def test_indented_fence_in_a_list(self):
        b, p = blocks(page('1. Step:', '', '   ' + F + 'sh', '   mvod --help', '   ' + F))
        self.assertEqual(p, [])
        self.assertEqual(b[0].text, 'mvod --help')

    def test_refusals(self):
        for text, what in [
                (page(F, 'mvod --help', F), 'without a language'),
                (page(F + 'bash', 'mvod --help', F), 'write shell examples as'),
                (page('<!-- not run: reasons: x -->', F + 'sh', 'ls', F), 'unknown category'),
                (page('<!-- not run because -->', F + 'sh', 'ls', F), 'write the marker'),
                (page('<!-- not run: camera: x -->', F + 'ini', 'a = 1', F), 'never runs'),
                (page(F + 'text', '$ mvod --help', F), 'shell example in a'),
                (page(F + 'sh', 'ls'), 'never closes')]:
            _, p = blocks(text)
            self.assertTrue(any(what in x for x in p), (text, p))


class Lcm(unittest.TestCase):
    def test_runs_that_stay_in_the_process(self):
        for script in ['mvod --source file:v.mkv --lcm-url memq://',
                       "mvod --source file:v.mkv --lcm-url 'file://run.lcmlog?mode=w'",
                       'mvod run --source x --lcm-url=memq://',
                       'mvod --source file:v.mkv \\\n     --calib c.json --lcm-url memq://',
                       "mvod view --lcm-url 'file://run.lcmlog?mode=r&speed=0' --png a.png",
                       'mvod --print-config', 'mvod --help', 'mvod bench --source x --gt y',
                       'mvod calibrate --source images:a --board b --out c.json',
                       'mvod speed-log gt.tum speed.lcmlog']:
            self.assertEqual(refused(script), [], script)

    def test_runs_that_would_publish(self):
        for script, what in [
                ('mvod --source file:v.mkv', 'without --lcm-url'),
                ('ls && mvod --source file:v.mkv --trajectory t.tum', 'without --lcm-url'),
                ('build/mvod run --config x.conf', 'without --lcm-url'),
                ('mvod view --png a.png', 'without --lcm-url'),
                ("build/examples/mvod-subscribe 'tcpq://127.0.0.1:7700'", 'names a tcpq:// URL'),
                ('mvod --source x --lcm-url tcpq://host', 'only memq:// or file://'),
                ('lcm-logger log.lcmlog', 'lcm-logger'),
                ('mvod --source x --lcm-url memq:// --trajectory /tmp/t.tum', '/tmp')]:
            p = refused(script)
            self.assertTrue(any(what in x for x in p), (script, p))

    def test_console_commands_are_checked(self):
        self.assertTrue(refused('$ mvod --source x\nmvod: 3 frames', 'console'))
        self.assertEqual(refused('$ mvod --source x --lcm-url memq://\nmvod: ...', 'console'), [])


class Output(unittest.TestCase):
    SUMMARY = 'mvod: 51 frames in 0.30 s (168.4 fps), 50 tracked, 1 held, front end klt'

    def test_timing_numbers_vary(self):
        self.assertTrue(ex.output_matches(
            [self.SUMMARY], ['mvod: 51 frames in 1.26 s (40 fps), 50 tracked, 1 held, front end klt']))
        self.assertTrue(ex.output_matches(['frame time median 8.8 ms, 95th percentile 19.0 ms'],
                                          ['frame time median 15.7 ms, 95th percentile 27.9 ms']))
        self.assertTrue(ex.output_matches(['status frames=3 scale=0 latency_ms=32.602'],
                                          ['status frames=3 scale=0 latency_ms=4.1']))

    def test_other_numbers_are_exact(self):
        self.assertFalse(ex.output_matches(
            [self.SUMMARY], ['mvod: 52 frames in 0.30 s (168.4 fps), 50 tracked, 1 held, front end klt']))
        self.assertFalse(ex.output_matches(['ATE 0.011 m over 59.9 m, 0.0 % (SE(3)-aligned)'],
                                           ['ATE 0.029 m over 59.9 m, 0.0 % (SE(3)-aligned)']))
        self.assertFalse(ex.output_matches(['status frames=3 scale=0'], ['status frames=3 scale=1']))
        self.assertFalse(ex.output_matches(['height 1.5996 m +- 2.3 mm'], ['height 1.5996 m +- 2.4 mm']))

    def test_dots(self):
        self.assertTrue(ex.output_matches(['a', '...', 'd'], ['a', 'b', 'c', 'd']))
        self.assertTrue(ex.output_matches(['a', '...', 'd'], ['a', 'd']))
        self.assertFalse(ex.output_matches(['a', 'd'], ['a', 'b', 'd']))
        self.assertFalse(ex.output_matches(['a'], ['a', 'b']))
        self.assertTrue(ex.output_matches(['capture ... pose'], ['capture 0.1 (2) detect 3 pose']))
        self.assertFalse(ex.output_matches(['capture ... pose'], ['capture 0.1', 'pose']))

    def test_console_parsing(self):
        cmds = ex.console_commands('$ mvod --source x \\\n       --lcm-url memq://\nline 1\n\n'
                                   '$ echo b\nb\n')
        self.assertEqual(cmds, [('mvod --source x \\\n       --lcm-url memq://', ['line 1']),
                                ('echo b', ['b'])])
        self.assertIsNone(ex.console_commands('output before any command\n$ ls\n'))


class Links(unittest.TestCase):
    def test_slugs(self):
        self.assertIn('measuring-the-mount-mvod-mount',
                      ex.anchors('## Measuring the mount: mvod mount\n'))
        self.assertIn('robot-speed---scale-external',
                      ex.anchors('### Robot speed: --scale external\n'))
        self.assertIn('a-1', ex.anchors('# A\n## A\n'))
        self.assertNotIn('not-a-heading', ex.anchors('```sh\n# not a heading\n```\n'))


if __name__ == '__main__':
    unittest.main()
