# Copyright 2026 py_vision contributors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
Every relative link in README.md and docs/*.md leads somewhere: a file, and a heading there.

Anchors are the ones GitHub makes from headings: the heading's text in lower case, without
punctuation other than '-' and '_', spaces turned into '-', and '-1', '-2', ... after repeats.
Links to web addresses are not followed.
"""

from pathlib import Path
import re
from urllib.parse import unquote

REPO = Path(__file__).resolve().parents[1]

_FENCE = re.compile(r'^(```|~~~).*?^\1[^\n]*$', re.MULTILINE | re.DOTALL)
_CODE_SPAN = re.compile(r'(`+).+?\1', re.DOTALL)
_INLINE_LINK = re.compile(r'!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+"[^"]*")?\s*\)')
_REFERENCE_LINK = re.compile(r'^ {0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$', re.MULTILINE)
_HEADING = re.compile(r'^ {0,3}#{1,6}[ \t]+(.*?)[ \t#]*$', re.MULTILINE)
_HTML_ANCHOR = re.compile(r'<a\s[^>]*(?:name|id)="([^"]+)"', re.IGNORECASE)
_SCHEME = re.compile(r'^[a-z][a-z0-9+.-]*:', re.IGNORECASE)


def documents(root):
    """Return the Markdown files whose links are checked: README.md and docs/*.md."""
    return [root / 'README.md'] + sorted((root / 'docs').glob('*.md'))


def _without_code(text):
    """Return text with fenced blocks and code spans blanked: links there are examples."""
    return _CODE_SPAN.sub('', _FENCE.sub('', text))


def _slug(heading):
    """Return GitHub's anchor for a heading's Markdown text."""
    text = re.sub(r'!?\[([^\]]*)\]\([^)]*\)', r'\1', heading)  # a link counts as its text
    text = re.sub(r'<[^>]+>', '', text).replace('`', '').lower()
    text = re.sub(r'[^\w\- ]', '', text)
    return text.replace(' ', '-')


def anchors(path):
    """Return the anchors a Markdown file offers: its headings' and explicit HTML ones."""
    text = path.read_text(encoding='utf-8')
    found = set(_HTML_ANCHOR.findall(text))
    seen = {}
    for heading in _HEADING.findall(_FENCE.sub('', text)):
        slug = _slug(heading)
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        found.add(slug if count == 0 else '%s-%d' % (slug, count))
    return found


def links(path):
    """Return the link targets written in a Markdown file, outside code."""
    text = _without_code(path.read_text(encoding='utf-8'))
    return _INLINE_LINK.findall(text) + _REFERENCE_LINK.findall(text)


def broken_links(root):
    """Return '<file>: <target>: <why>' for every relative link under root that leads nowhere."""
    broken = []
    for doc in documents(root):
        for target in links(doc):
            if not target or _SCHEME.match(target):
                continue
            path_part, _, anchor = target.partition('#')
            destination = (doc.parent / unquote(path_part)).resolve() if path_part else doc
            where = '%s: %s' % (doc.relative_to(root), target)
            if not destination.exists():
                broken.append('%s: no such file' % where)
            elif anchor and (destination.suffix != '.md' or destination.is_dir()):
                broken.append('%s: an anchor into a file that is not Markdown' % where)
            elif anchor and unquote(anchor) not in anchors(destination):
                broken.append('%s: no heading with that anchor in %s' % (
                    where, destination.relative_to(root) if root in destination.parents
                    else destination))
    return broken


def test_every_relative_link_leads_to_a_file_and_heading():
    broken = broken_links(REPO)
    assert not broken, '%d broken link(s):\n%s' % (len(broken), '\n'.join(broken))


def test_broken_links_and_anchors_are_found(tmp_path):
    (tmp_path / 'docs').mkdir()
    (tmp_path / 'docs' / 'guide.md').write_text(
        '# Guide\n\n## The `petalinux/` tool: step 1\n\n## Repeat\n\n## Repeat\n\n'
        '```sh\n# not a heading\n```\n[back](../README.md#top)\n', encoding='utf-8')
    (tmp_path / 'README.md').write_text(
        '# Top\n\n[guide](docs/guide.md) [tool](docs/guide.md#the-petalinux-tool-step-1) '
        '[second](docs/guide.md#repeat-1) ![picture](docs/missing.png) '
        '[gone](docs/guide.md#not-a-heading) [web](https://example.com/x.md) '
        '[self](#top) [nope](#nowhere) `[code](docs/also-missing.md)`\n\n'
        '```\n[fenced](docs/fenced-missing.md)\n```\n', encoding='utf-8')
    assert broken_links(tmp_path) == [
        'README.md: docs/missing.png: no such file',
        'README.md: docs/guide.md#not-a-heading: no heading with that anchor in '
        'docs/guide.md',
        'README.md: #nowhere: no heading with that anchor in README.md',
    ]
