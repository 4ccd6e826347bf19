"""Checks every relative link of the Markdown documentation: the file exists and, for a
link with #anchor, the target file has a heading with that GitHub anchor. Usage:
python3 .ci/doclinks.py README.md ARCHITECTURE.md CONTRIBUTING.md docs/*.md (exit 1 on a
broken link, naming its file and line)."""
import re, sys, os, unicodedata
def slug(h):
    h = h.strip().lower()
    out = []
    for ch in h:
        cat = unicodedata.category(ch)
        if ch in " -": out.append("-" if ch == " " else ch)
        elif cat[0] in "LNM" or cat == "Pc": out.append(ch)
    return "".join(out)
def headings(path):
    seen = {}; res = set(); code = False
    for l in open(path, encoding="utf-8"):
        if l.startswith("```"): code = not code; continue
        if code: continue
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", l)
        if m:
            s = slug(re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", m.group(1)))
            n = seen.get(s, 0); seen[s] = n + 1
            res.add(s if n == 0 else f"{s}-{n}")
    return res
bad = 0; count = 0
for f in sys.argv[1:]:
    code = False
    for i, l in enumerate(open(f, encoding="utf-8"), 1):
        if l.startswith("```"): code = not code; continue
        if code: continue
        l2 = re.sub(r"`[^`]*`", "", l)
        for m in re.finditer(r"\]\(([^)\s]+)\)", l2):
            t = m.group(1)
            if re.match(r"^[a-z]+:", t): continue
            count += 1
            p, _, a = t.partition("#")
            target = os.path.normpath(os.path.join(os.path.dirname(f), p)) if p else f
            if not os.path.exists(target):
                print(f"{f}:{i}: missing file {t}"); bad += 1; continue
            if a:
                if not target.endswith(".md"):
                    print(f"{f}:{i}: anchor on non-md {t}"); bad += 1
                elif a not in headings(target):
                    print(f"{f}:{i}: missing anchor {t}"); bad += 1
print(f"{count} relative links checked, {bad} broken")
sys.exit(1 if bad else 0)
