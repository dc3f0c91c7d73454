/* mitsuba_check.h - checks the text of a Mitsuba 3 XML scene written by pdftrace_scene.h's
   pt_scenefile_export_mitsuba: plain ASCII; one XML declaration, then elements that nest and
   close, under a single <scene>; comments without "--" inside; attribute values quoted, without
   '<', and '&' only as one of XML's five entities; every number of a float, integer, rgb,
   point, vector, matrix or lookat element finite (no nan, no inf). Used by the fuzz harness and
   the tests. */
#ifndef PT_MITSUBA_CHECK_H
#define PT_MITSUBA_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PT__MC_DEPTH 16

static int pt__mc_fail(char *why, size_t n, const char *msg, size_t at)
{
    if (why && n) snprintf(why, n, "%s (at byte %lu)", msg, (unsigned long)at);
    return 0;
}

/* The numbers of a value: separated by blanks or commas, each read whole by strtod and finite. */
static int pt__mc_numbers(const char *v, size_t len)
{
    char buf[1024];
    char *p, *end;
    if (len == 0 || len >= sizeof buf) return 0;
    memcpy(buf, v, len);
    buf[len] = '\0';
    for (p = buf; *p;) {
        double x;
        while (*p == ' ' || *p == ',') ++p;
        if (!*p) break;
        x = strtod(p, &end);
        if (end == p || !(x == x) || fabs(x) > 3.4e38) return 0;
        if (*end && *end != ' ' && *end != ',') return 0;
        p = end;
    }
    return 1;
}

/* One attribute value [v, v + len): no '<', entities only. */
static int pt__mc_value(const char *v, size_t len)
{
    static const char *const ent[] = {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"};
    size_t i, k;
    for (i = 0; i < len; ++i) {
        if (v[i] == '<') return 0;
        if (v[i] == '&') {
            for (k = 0; k < 5; ++k)
                if (len - i >= strlen(ent[k]) && !strncmp(v + i, ent[k], strlen(ent[k]))) break;
            if (k == 5) return 0;
        }
    }
    return 1;
}

/* The attributes of a start tag [s, e); numbers: the tag's values must be numbers. */
static int pt__mc_attrs(const char *s, const char *e, int numbers, char *why, size_t n, size_t at)
{
    while (s < e) {
        const char *name = s, *q;
        while (s < e && *s == ' ') ++s;
        if (s >= e) break;
        name = s;
        while (s < e && ((*s >= 'a' && *s <= 'z') || *s == '_')) ++s;
        if (s == name || s + 1 >= e || s[0] != '=' || s[1] != '"') return pt__mc_fail(why, n, "bad attribute", at);
        s += 2;
        q = (const char *)memchr(s, '"', (size_t)(e - s));
        if (!q) return pt__mc_fail(why, n, "unterminated attribute value", at);
        if (!pt__mc_value(s, (size_t)(q - s))) return pt__mc_fail(why, n, "'<' or a bare '&' in an attribute value", at);
        if (numbers && strncmp(name, "name=", 5) && !pt__mc_numbers(s, (size_t)(q - s)))
            return pt__mc_fail(why, n, "a number that is not finite, or not a number", at);
        s = q + 1;
    }
    return 1;
}

/* 1 if text[0..len) is such a scene; else 0 with the reason in why. */
static int pt_mitsuba_check_text(const char *text, size_t len, char *why, size_t why_size)
{
    static const char decl[] = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n";
    char stack[PT__MC_DEPTH][16];
    int depth = 0, roots = 0;
    size_t i = 0;
    for (i = 0; i < len; ++i)
        if (!((text[i] >= 0x20 && text[i] < 0x7f) || text[i] == '\n'))
            return pt__mc_fail(why, why_size, "a byte that is not printable ASCII", i);
    if (len < sizeof decl - 1 || memcmp(text, decl, sizeof decl - 1))
        return pt__mc_fail(why, why_size, "no XML declaration", 0);
    for (i = sizeof decl - 1; i < len;) {
        const char *s = text + i, *e;
        size_t nl;
        if (*s == ' ' || *s == '\n') { ++i; continue; }
        if (*s != '<') return pt__mc_fail(why, why_size, "text outside a tag", i);
        if (len - i >= 4 && !strncmp(s, "<!--", 4)) {
            const char *c = s + 4;
            e = NULL;
            for (; c + 1 < text + len; ++c)
                if (c[0] == '-' && c[1] == '-') { e = c; break; }
            if (!e || e + 2 >= text + len || e[2] != '>' || e[-1] == '-')
                return pt__mc_fail(why, why_size, "a comment holds \"--\" or does not end", i);
            i = (size_t)(e + 3 - text);
            continue;
        }
        e = (const char *)memchr(s, '>', len - i);
        if (!e) return pt__mc_fail(why, why_size, "unterminated tag", i);
        if (memchr(s + 1, '<', (size_t)(e - s - 1))) return pt__mc_fail(why, why_size, "'<' inside a tag", i);
        if (s[1] == '/') {
            nl = (size_t)(e - s - 2);
            if (depth == 0 || nl != strlen(stack[depth - 1]) || strncmp(s + 2, stack[depth - 1], nl))
                return pt__mc_fail(why, why_size, "a closing tag that does not match", i);
            --depth;
        } else {
            const char *name = s + 1, *ne = name;
            int empty = e[-1] == '/', numbers;
            while ((*ne >= 'a' && *ne <= 'z') || *ne == '_') ++ne;
            nl = (size_t)(ne - name);
            if (nl == 0 || nl >= sizeof stack[0]) return pt__mc_fail(why, why_size, "bad element name", i);
            if (depth == 0 && (roots++ || nl != 5 || strncmp(name, "scene", 5)))
                return pt__mc_fail(why, why_size, "not a single <scene> root", i);
            numbers = (nl == 5 && !strncmp(name, "float", 5)) || (nl == 7 && !strncmp(name, "integer", 7)) ||
                      (nl == 3 && !strncmp(name, "rgb", 3)) || (nl == 5 && !strncmp(name, "point", 5)) ||
                      (nl == 6 && !strncmp(name, "matrix", 6)) || (nl == 6 && !strncmp(name, "vector", 6)) ||
                      (nl == 6 && !strncmp(name, "lookat", 6));
            if (!pt__mc_attrs(ne, empty ? e - 1 : e, numbers, why, why_size, i)) return 0;
            if (!empty) {
                if (depth == PT__MC_DEPTH) return pt__mc_fail(why, why_size, "elements nested too deep", i);
                memcpy(stack[depth], name, nl);
                stack[depth++][nl] = '\0';
            }
        }
        i = (size_t)(e + 1 - text);
    }
    if (depth != 0 || roots != 1) return pt__mc_fail(why, why_size, "an element is not closed, or no <scene>", len);
    return 1;
}

#endif
