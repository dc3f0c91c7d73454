/* gen_mesh.c - writes the torus used by scenes/mesh.scene as a Wavefront OBJ with vertex
   normals (v, vn, f a//a b//b c//c).  build: cc -O2 -o gen_mesh gen_mesh.c -lm
   usage: gen_mesh OUT.obj   (the committed scenes/mesh.obj is its output)
   Torus of major radius R about the y axis, minor radius r: p(u,v) = ((R + r cos v) cos u,
   r sin v, (R + r cos v) sin u); the unit normal is (cos v cos u, sin v, cos v sin u). */
#include <math.h>
#include <stdio.h>

#define NU 48
#define NV 24

int main(int argc, char **argv)
{
    const double R = 0.8, r = 0.3, pi = 3.14159265358979323846;
    FILE *f;
    int i, j;
    if (argc != 2) { fprintf(stderr, "usage: gen_mesh OUT.obj\n"); return 2; }
    f = fopen(argv[1], "w");
    if (!f) { perror(argv[1]); return 1; }
    fprintf(f, "# torus R=%g r=%g, %d x %d quads split in triangles; written by validation/gen_mesh.c\n", R, r, NU, NV);
    for (i = 0; i < NU; i++)
        for (j = 0; j < NV; j++) {
            double u = 2 * pi * i / NU, v = 2 * pi * j / NV;
            fprintf(f, "v %.6f %.6f %.6f\n", (R + r * cos(v)) * cos(u), r * sin(v), (R + r * cos(v)) * sin(u));
        }
    for (i = 0; i < NU; i++)
        for (j = 0; j < NV; j++) {
            double u = 2 * pi * i / NU, v = 2 * pi * j / NV;
            fprintf(f, "vn %.6f %.6f %.6f\n", cos(v) * cos(u), sin(v), cos(v) * sin(u));
        }
    for (i = 0; i < NU; i++)
        for (j = 0; j < NV; j++) {
            int a = i * NV + j + 1, b = ((i + 1) % NU) * NV + j + 1;
            int c = ((i + 1) % NU) * NV + (j + 1) % NV + 1, d = i * NV + (j + 1) % NV + 1;
            /* counter-clockwise seen from outside */
            fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, d, d, c, c);
            fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, c, c, b, b);
        }
    if (fclose(f) != 0) { perror(argv[1]); return 1; }
    return 0;
}
