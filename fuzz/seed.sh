#!/bin/sh
# Seeds corpus/<target>/ from the conformance vectors (spec/vectors/*.qcs), with the control bytes
# each harness expects in front (see harness/src/lib.rs). The seeds are not committed.
set -e
cd "$(dirname "$0")"
for t in decode push header roundtrip; do mkdir -p corpus/$t; done
for f in ../spec/vectors/*.qcs; do
    n=$(basename "$f" .qcs)
    { printf '\040\030\000'; cat "$f"; } > corpus/decode/$n
    { printf '\020\020\201'; cat "$f"; } > corpus/decode/$n-cap
    { printf '\003\002\101'; cat "$f"; } > corpus/decode/$n-thumb
    { printf 'seed'; cat "$f"; } > corpus/push/$n
    { printf '\001\002\003\004'; cat "$f"; } > corpus/push/$n-b
    head -c 64 "$f" > corpus/header/$n
done
printf '\027\027\002\007\200\007\003\000 gradient pixels 0123456789' > corpus/roundtrip/rgb
printf '\017\011\000\004\060\002\001\005\000\377\200\177' > corpus/roundtrip/grey-frame
printf '\003\003\003\000\011\001\000\000' > corpus/roundtrip/rgba-constant
printf '\027\023\002\010\000\200\003\000 the header defaults bit' > corpus/roundtrip/rgb-defaults
# With a refinement (the top bits of the bits byte): lossless, a quality, a size.
printf '\027\023\003\107\024\003\004\000 lossless rgba pixels' > corpus/roundtrip/rgba-lossless
printf '\011\015\000\205\113\001\000\000 grey at quality 75' > corpus/roundtrip/grey-q75
printf '\020\020\002\301\144\002\002\000 rgb in 400 bytes' > corpus/roundtrip/rgb-size
