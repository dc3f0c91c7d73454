#!/bin/sh
# tests/lint_headers.sh - size limits for the header family (make check-warnings runs it).
#
#   tests/lint_headers.sh [header.h ...]     (default: pdftrace*.h in the current directory)
#
# Reports, one line each as file:line: what,
#   - every comment longer than MAX_COMMENT lines (default 25) after the header's
#     implementation marker (the first line `#ifdef PDFTRACE..._IMPLEMENTATION`) and before
#     its closing `#endif /* PDFTRACE..._IMPLEMENTATION */` (the licence follows); comments
#     that follow each other with no blank line or code between count as one (a code line
#     whose trailing comment ends on that line is code, not comment);
#   - every function longer than MAX_FUNCTION lines (default 150) anywhere in the header,
#     counted from the line that opens its body (a `{` alone at column 0, the house style) to
#     the line that closes it (a `}` alone at column 0).
# Exits 1 when anything is reported, 0 otherwise. The top-of-file documentation and the
# declarations' comments are not limited: they are the API reference.

MAX_COMMENT=${MAX_COMMENT:-25}
MAX_FUNCTION=${MAX_FUNCTION:-150}

if [ $# -eq 0 ]; then
    set -- pdftrace*.h
fi

status=0
for f in "$@"; do
    if [ ! -f "$f" ]; then
        echo "$f: no such file" >&2
        status=1
        continue
    fi
    awk -v file="$f" -v maxc="$MAX_COMMENT" -v maxf="$MAX_FUNCTION" '
    # A character-level scan that knows string and character literals, // and /* */ comments.
    BEGIN { impl = 0; incomment = 0; cstart = 0; cend = -10; bad = 0; fstart = 0; prevname = "" }
    function flush_comment() {
        if (cstart > 0 && cend - cstart + 1 > maxc) {
            printf "%s:%d: comment of %d lines (limit %d)\n", file, cstart, cend - cstart + 1, maxc
            bad = 1
        }
        cstart = 0
    }
    {
        line = $0
        if (!impl && !incomment && line ~ /^#ifdef PDFTRACE[A-Z_]*_IMPLEMENTATION[ \t]*$/) impl = 1
        # the implementation part ends at its closing #endif (the licence text follows it)
        if (impl && !incomment && line ~ /^#endif \/\* PDFTRACE[A-Z_]*_IMPLEMENTATION \*\/$/) { flush_comment(); impl = 0 }
        # functions: a body opens with "{" alone at column 0 and closes with "}" alone at column 0
        if (line == "{") { fstart = NR; fname = prevname }
        else if (line == "}" && fstart > 0) {
            if (NR - fstart + 1 > maxf) {
                printf "%s:%d: function %s of %d lines (limit %d)\n", file, fstart, fname, NR - fstart + 1, maxf
                bad = 1
            }
            fstart = 0
        }
        if (line ~ /^[A-Za-z_].*\(/) {
            name = line
            sub(/\(.*/, "", name)
            n = split(name, parts, /[ \t*]+/)
            prevname = parts[n]
        }
        # comments: a comment line holds a comment and no code, or is part of a comment that
        # runs over several lines
        started = incomment; hascomment = incomment; code = 0
        i = 1; len = length(line); instr = ""
        while (i <= len) {
            c = substr(line, i, 1)
            if (incomment) {
                if (c == "*" && substr(line, i + 1, 1) == "/") { incomment = 0; i += 2; continue }
                i++; continue
            }
            if (instr != "") {
                if (c == "\\") { i += 2; continue }
                if (c == instr) instr = ""
                i++; continue
            }
            if (c == "\"" || c == "\047") { instr = c; code = 1; i++; continue }
            if (c == "/" && substr(line, i + 1, 1) == "*") { incomment = 1; hascomment = 1; i += 2; continue }
            if (c == "/" && substr(line, i + 1, 1) == "/") { hascomment = 1; break }
            if (c != " " && c != "\t") code = 1
            i++
        }
        hascomment = hascomment && (!code || started || incomment)
        if (impl && hascomment) {
            if (cstart == 0) cstart = NR
            else if (cend < NR - 1) { flush_comment(); cstart = NR }
            cend = NR
        } else if (impl && cstart > 0 && cend < NR) {
            flush_comment()
        }
    }
    END { if (impl) flush_comment(); exit bad }
    ' "$f" || status=1
done
exit $status
