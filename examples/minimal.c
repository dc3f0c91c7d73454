#define _POSIX_C_SOURCE 200809L
/* minimal.c - a sphere on a floor under a quad light, written to argv[1] (default minimal.ppm). */
#include <stdio.h>
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "minimal.ppm";
    pt_render_desc d = {0}; /* zero means "default" for every field */
    pt_image img = {0};
    char err[512] = "";
    pt_render_stats st;
    pt_scene *s = pt_scene_create();
    int white, light, rc = s ? PT_OK : PT_ERROR_OUT_OF_MEMORY;

    if (rc == PT_OK && (rc = white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f))) >= 0 &&
        (rc = light = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0)) >= 0 &&   /* one-sided, emits along u x v */
        (rc = pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white)) >= 0 && /* floor */
        (rc = pt_scene_add_quad(s, pt_v3(-1, 4, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), light)) >= 0 &&   /* u x v = -y */
        (rc = pt_scene_add_sphere(s, pt_v3(0, 1, 0), 1, white)) >= 0)
        rc = pt_scene_commit(s);
    if (rc < 0) {
        fprintf(stderr, "minimal: scene: %s %s\n", pt_result_string(rc), s ? pt_scene_error_message(s) : "");
        if (s) pt_scene_destroy(s);
        return 1;
    }
    d.width = 320; d.height = 240; d.samples_per_pixel = 64;
    d.camera.look_from = pt_v3(0, 2, -8); d.camera.look_at = pt_v3(0, 1, 0);
    d.background = pt_v3(0.01f, 0.01f, 0.02f); /* a faint night sky */
    if ((rc = pt_render_image(s, &d, &img, &st)) == PT_OK && (rc = pt_write_ppm_ex(path, &img, err, sizeof err)) == PT_OK)
        printf("wrote %s: %dx%d, %d spp in %.2f s\n", path, d.width, d.height, d.samples_per_pixel, st.seconds);
    else
        fprintf(stderr, "minimal: %s\n", err[0] ? err : pt_result_string(rc)); /* err names the path and the reason */
    pt_image_free(&img);
    pt_scene_destroy(s);
    return rc == PT_OK ? 0 : 1;
}
