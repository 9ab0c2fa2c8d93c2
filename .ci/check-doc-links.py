#!/usr/bin/env python3
"""Every relative link and image in the repository's Markdown resolves: the file exists
(in git), and a #fragment names a heading of the target. External links are not
fetched. Also refuses paths that reach outside the repository."""
import re, subprocess, sys, os

root = subprocess.check_output(['git', 'rev-parse', '--show-toplevel'], text=True).strip()
os.chdir(root)
tracked = set(subprocess.check_output(['git', 'ls-files'], text=True).split('\n'))
tracked |= {os.path.dirname(p) for p in tracked}
files = [f for f in tracked if f.endswith('.md') and not f.startswith(('tests/fuzz/corpus',))]

def anchors(path):
    out = set()
    in_code = False
    for line in open(path, encoding='utf-8'):
        if line.startswith('```'):
            in_code = not in_code
        if in_code or not line.startswith('#'):
            continue
        title = line.lstrip('#').strip().lower()
        slug = re.sub(r'[^\w\- ]', '', title).replace(' ', '-')
        out.add(slug)
    return out

bad = []
link = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)\)')
for f in sorted(files):
    text = open(f, encoding='utf-8').read()
    text = re.sub(r'```.*?```', '', text, flags=re.S)
    for target in link.findall(text):
        if re.match(r'[a-z]+:', target):
            continue
        path, _, frag = target.partition('#')
        resolved = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
        if resolved.startswith('..'):
            bad.append(f'{f}: {target}: outside the repository')
        elif resolved not in tracked:
            bad.append(f'{f}: {target}: no such file in the repository')
        elif frag and resolved.endswith('.md') and frag not in anchors(resolved):
            bad.append(f'{f}: {target}: no heading #{frag}')
for b in bad:
    print(b)
sys.exit(1 if bad else 0)
