#!/usr/bin/env bash
# Vendors KaTeX (https://katex.org, MIT licence) into docs/src/vendor/katex/ so that the book's
# equations render with no network: mdBook copies the folder into the built book and
# docs/theme/head.hbs loads it on every page. Run from anywhere, with npm installed:
#
#     docs/update_katex.sh [VERSION]      # default: the version in docs/src/vendor/katex/VERSION
#
# Kept: katex.min.js, katex.min.css, contrib/auto-render.min.js, the WOFF2 fonts (every browser
# in use reads WOFF2) and the licence. The stylesheet's fallback `url(...)` entries for the WOFF
# and TrueType copies are removed, so that every font it names is present
# (.ci/check_math.py checks that).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dest="$here/src/vendor/katex"
version="${1:-$(cat "$dest/VERSION" 2>/dev/null || echo latest)}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent "katex@$version" >/dev/null && tar xzf katex-*.tgz)
dist="$tmp/package/dist"
rm -rf "$dest"
mkdir -p "$dest/contrib" "$dest/fonts"
cp "$dist/katex.min.js" "$dest/"
cp "$dist/contrib/auto-render.min.js" "$dest/contrib/"
cp "$dist"/fonts/*.woff2 "$dest/fonts/"
cp "$tmp/package/LICENSE" "$dest/LICENSE"
python3 - "$dist/katex.min.css" "$dest/katex.min.css" <<'PY'
import re, sys
css = open(sys.argv[1], encoding="utf-8").read()
css, n = re.subn(r',url\(fonts/[^)]*\.(?:woff|ttf)\) format\("(?:woff|truetype)"\)', "", css)
assert n > 0 and ".woff)" not in css and ".ttf)" not in css, "unexpected katex.min.css layout"
open(sys.argv[2], "w", encoding="utf-8").write(css)
PY
version="$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['version'])" "$tmp/package/package.json")"
echo "$version" > "$dest/VERSION"
echo "KaTeX $version vendored into $dest"
