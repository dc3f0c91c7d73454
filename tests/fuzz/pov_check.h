/* pov_check.h - a checker for the text pt_scenefile_write_pov writes, shared by the fuzz
   harness (tests/fuzz/harness.c, target pov) and the unit tests (tests/test_pov.c).
   pt_pov_check_text(text, len, why, why_size) returns 1 when the text is safe and plausible:
   - only printable ASCII and '\n' (no CR, form feed or other byte that may end a line);
   - '#' only in the exporter's two fixed directive lines: no other POV-Ray directive
     (#fopen, #write, #include, #declare, ...) can appear;
   - no '"' (the exporter writes no string literal) and no block comment ("/" "*" or "*" "/");
   - a comment is a whole line starting with "//";
   - every other line holds only numbers, punctuation and identifiers from the exporter's
     own vocabulary (so neither nan/inf nor any word taken from input);
   - braces balanced, never closed before they are opened.
   On failure `why` says what and on which line. */
#ifndef PT_POV_CHECK_H
#define PT_POV_CHECK_H

#include <stdio.h>
#include <string.h>

static int pt_pov_check_keyword(const char *s, size_t n)
{
    static const char *const words[] = {
        "global_settings", "assumed_gamma", "ambient_light", "max_trace_level", "adc_bailout", "radiosity",
        "brightness", "gray_threshold", "count", "error_bound", "recursion_limit", "nearest_count",
        "pretrace_start", "pretrace_end", "minimum_reuse", "maximum_reuse", "low_error_factor", "background",
        "rgb", "rgbf", "camera", "perspective", "location", "right", "x", "up", "y", "direction", "z", "angle",
        "sky", "look_at", "light_source", "spotlight", "parallel", "point_at", "radius", "falloff", "tightness",
        "fade_distance", "fade_power", "sphere", "mesh", "mesh2", "triangle", "box", "matrix", "vertex_vectors",
        "normal_vectors", "face_indices", "texture", "pigment", "checker", "scale", "finish", "diffuse",
        "emission", "reflection", "fresnel", "on", "conserve_energy", "interior", "ior", "no_shadow",
        "no_radiosity", "no_image", "no_reflection"};
    size_t i;
    for (i = 0; i < sizeof words / sizeof words[0]; ++i)
        if (strlen(words[i]) == n && memcmp(words[i], s, n) == 0) return 1;
    return 0;
}

/* One line of code (not a comment, not a fixed directive); updates the brace depth. */
static int pt_pov_check_code(const char *s, size_t n, long *depth, char *why, size_t why_size, long line)
{
    size_t i = 0;
    while (i < n) {
        char c = s[i];
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_') {
            size_t j = i;
            while (j < n && ((s[j] >= 'a' && s[j] <= 'z') || (s[j] >= 'A' && s[j] <= 'Z') || s[j] == '_' ||
                             (s[j] >= '0' && s[j] <= '9')))
                ++j;
            if (!pt_pov_check_keyword(s + i, j - i)) {
                int nonfinite = (j - i == 3 && (!memcmp(s + i, "nan", 3) || !memcmp(s + i, "inf", 3))) ||
                                (j - i == 8 && !memcmp(s + i, "infinity", 8));
                snprintf(why, why_size, "line %ld: %s '%.*s'", line, nonfinite ? "non-finite number" : "unknown word",
                         (int)(j - i), s + i);
                return 0;
            }
            i = j;
        } else if ((c >= '0' && c <= '9') || c == '.') {
            while (i < n && ((s[i] >= '0' && s[i] <= '9') || s[i] == '.')) ++i;
            if (i < n && (s[i] == 'e' || s[i] == 'E')) {
                ++i;
                if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
                if (!(i < n && s[i] >= '0' && s[i] <= '9')) {
                    snprintf(why, why_size, "line %ld: malformed number", line);
                    return 0;
                }
                while (i < n && s[i] >= '0' && s[i] <= '9') ++i;
            }
        } else if (c == '{' || c == '}') {
            *depth += c == '{' ? 1 : -1;
            if (*depth < 0) {
                snprintf(why, why_size, "line %ld: '}' without '{'", line);
                return 0;
            }
            ++i;
        } else if (c && strchr(" <>,-+*;", c)) {
            ++i;
        } else {
            snprintf(why, why_size, "line %ld: unexpected character '%c'", line, c);
            return 0;
        }
    }
    return 1;
}

static int pt_pov_check_text(const char *text, size_t len, char *why, size_t why_size)
{
    static const char *const fixed[] = {"#version 3.7;", "#default { finish { ambient 0 emission 0 diffuse 1 } }"};
    size_t i, start = 0;
    long depth = 0, line = 1;
    for (i = 0; i < len; ++i) {
        unsigned char c = (unsigned char)text[i];
        if (c != '\n' && (c < 0x20 || c > 0x7e)) {
            snprintf(why, why_size, "line %ld: byte 0x%02x (only printable ASCII and newlines)", line, c);
            return 0;
        }
        if (c == '"') { snprintf(why, why_size, "line %ld: a string literal", line); return 0; }
        if (i + 1 < len && ((c == '/' && text[i + 1] == '*') || (c == '*' && text[i + 1] == '/'))) {
            snprintf(why, why_size, "line %ld: a block comment delimiter", line);
            return 0;
        }
    }
    while (start < len) {
        const char *s = text + start;
        size_t n = 0, k;
        int is_fixed = 0;
        while (start + n < len && s[n] != '\n') ++n;
        for (k = 0; k < sizeof fixed / sizeof fixed[0]; ++k)
            if (strlen(fixed[k]) == n && memcmp(fixed[k], s, n) == 0) is_fixed = 1;
        if (!(n >= 2 && s[0] == '/' && s[1] == '/')) { /* comments are whole lines and may hold no '#' */
            if (memchr(s, '/', n)) { snprintf(why, why_size, "line %ld: '/' in code (a comment not at the start)", line); return 0; }
        } else if (memchr(s, '#', n)) {
            snprintf(why, why_size, "line %ld: '#' in a comment", line);
            return 0;
        }
        if (!is_fixed && !(n >= 2 && s[0] == '/' && s[1] == '/')) {
            if (memchr(s, '#', n)) { snprintf(why, why_size, "line %ld: a directive ('#')", line); return 0; }
            if (!pt_pov_check_code(s, n, &depth, why, why_size, line)) return 0;
        }
        start += n + 1;
        ++line;
    }
    if (depth != 0) { snprintf(why, why_size, "%ld unclosed '{'", depth); return 0; }
    if (len == 0 || text[len - 1] != '\n') { snprintf(why, why_size, "empty, or the last line is not terminated"); return 0; }
    return 1;
}

#endif
