#!/usr/bin/env python3
"""Where a sample's time goes: the samples of `perf record` (no call graph needed) attributed to
the integrator's stages by the chain of functions inlined at each sampled address (addr2line -i).

    cc -I. -std=c99 -O3 -g -pthread -o build/pdftrace_g tools/pdftrace.c -lm
    perf record -o perf.data build/pdftrace_g scenes/cornell-diffuse.scene --size 300x300 --spp 16 \\
        --threads 1 -o /tmp/x.pfm
    python3 bench/perf_stages.py build/pdftrace_g perf.data

A sample goes to the first stage (in the order below) any function of its inline chain belongs
to; the rest is "path logic/other" (the integrator's own code, vector math, branches). Samples
outside the program's symbols are "unmapped". Needs perf, nm and addr2line (binutils)."""
import collections
import re
import subprocess
import sys

STAGES = [
    ('shadow rays (any-hit)', ['pt__scene_any', 'pt__bvh_any', 'pt__light_visible', 'pt__leaf_any', 'pt__rtc_any',
                               'pt__packet_any', 'pt__batch_shadow']),
    ('closest-hit traversal', ['pt__packet', 'pt__batch_closest', 'pt__scene_closest', 'pt__bvh_closest',
                               'pt__bvh_trace', 'pt__leaf_closest', 'pt__rtc_closest']),
    ('film', ['pt__film_sample', 'pt__dd_add', 'pt__two_sum']),
    ('camera', ['pt__camera_ray']),
    ('sampler', ['pt__draw', 'pt_rng', 'pt__sampler', 'pt__sobol', 'pt__owen']),
    ('hit record', ['pt__fill_hit', 'pt__albedo']),
    # (before light sampling: next-event estimation's f, pt__material_eval in pt__nee_prepare, is the material's)
    ('material sample/eval/density', ['pt__material', 'pt__scatter', 'pt__lambert', 'pt__cosine', 'pt__onb', 'pt__fresnel',
                                      'pt__reflect', 'sincos']),
    # the light sample and its shadow ray's set-up, in the scalar integrator and in the batched one's
    # stages 2, 2b, 2c and 2s (pt__lane_light, pt__batch_lights, pt__batch_area_lights, pt__batch_sphere_lights
    # and what they inline)
    ('light sampling and light pmf', ['pt__lights_sample', 'pt__lights_pick', 'pt__planar_', 'pt__light_pmf',
                                      'pt__light_prim_value', 'pt__lights_value', 'pt__lights_reachable',
                                      'pt__sphere_light', 'pt__lnode', 'pt__sphrect', 'pt__light_shadow_ray',
                                      'pt__light_target', 'pt__nee_prepare', 'pt__lane_light', 'pt__lane_pick',
                                      'pt__lane_area', 'pt__batch_lights', 'pt__batch_area_lights', 'pt__quad_area8',
                                      'pt__qa_', 'pt__batch_sphere_lights', 'pt__sphere_sample8', 'pt__in_cone']),
]


def main():
    if len(sys.argv) != 3:
        sys.exit('usage: perf_stages.py BINARY PERF_DATA')
    binary, data = sys.argv[1], sys.argv[2]
    out = subprocess.run(['perf', 'script', '-i', data, '-F', 'ip,sym,symoff'], capture_output=True, text=True,
                         check=True).stdout
    count = collections.Counter(l.split(None, 1)[1].strip() for l in out.splitlines() if len(l.split()) > 1)
    syms = {}
    for line in subprocess.run(['nm', binary], capture_output=True, text=True, check=True).stdout.splitlines():
        p = line.split()
        if len(p) == 3:
            syms[p[2]] = int(p[0], 16)
    keys, query = [], []
    for k in count:
        m = re.match(r'(\S+)\+0x([0-9a-f]+)', k)
        if m and m.group(1) in syms:
            keys.append(k)
            query += [hex(syms[m.group(1)] + int(m.group(2), 16)), '0x0']  # 0x0: a separator ("??")
    res = subprocess.run(['addr2line', '-i', '-f', '-e', binary], input='\n'.join(query) + '\n', capture_output=True,
                         text=True, check=True).stdout.splitlines()
    chains, cur = [], []
    for i in range(0, len(res) - 1, 2):
        if res[i] == '??' and res[i + 1].startswith('??'):
            chains.append(cur)
            cur = []
        else:
            cur.append(res[i])
    total = collections.Counter()
    mapped = 0
    for k, chain in zip(keys, chains):
        label = 'path logic/other'
        for name, prefixes in STAGES:
            if any(p in f for f in chain for p in prefixes):
                label = name
                break
        total[label] += count[k]
        mapped += count[k]
    n = sum(count.values())
    for label, c in total.most_common():
        print('%5.1f %%  %s' % (100.0 * c / n, label))
    print('%5.1f %%  unmapped' % (100.0 * (n - mapped) / n))


if __name__ == '__main__':
    main()
