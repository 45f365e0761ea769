#!/usr/bin/env bash
# Builds the book with the API documentation inside it, as CI does, then checks its links and
# its equations. From anywhere:  docs/build.sh   then open docs/book/index.html.
# Needs mdbook 0.5.x (`cargo install mdbook --locked --version 0.5.4`); no network at build or
# reading time (the equations use the KaTeX copy in docs/src/vendor/katex/).
set -euo pipefail
cd "$(dirname "$0")/.."
mdbook build docs
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace --lib
rm -rf docs/book/rustdoc && cp -r target/doc docs/book/rustdoc
python3 .ci/check_links.py docs/book
python3 .ci/check_math.py docs/book
