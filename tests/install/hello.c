/* hello.c - built by tests/install/check.sh (make install-check) against an installed pdftrace:
   `#include <pdftrace.h>` found through `pkg-config --cflags pdftrace`, linked with
   `pkg-config --libs pdftrace`. Renders a sphere on a floor under a quad light, 32 x 24 pixels at
   8 samples per pixel, and fails unless the render succeeds and the image is lit. */
#define PDFTRACE_IMPLEMENTATION
#include <pdftrace.h>

#include <stdio.h>

int main(void)
{
    pt_scene *s = pt_scene_create();
    pt_render_desc d = {0};
    pt_image img = {0, 0, NULL};
    double sum = 0;
    int white, lamp, rc, i;
    if (!s) return 1;
    white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    lamp = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0);
    pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white);
    pt_scene_add_quad(s, pt_v3(-1, 4, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), lamp);
    pt_scene_add_sphere(s, pt_v3(0, 1, 0), 1, white);
    rc = pt_scene_commit(s);
    if (rc == PT_OK) {
        d.width = 32; d.height = 24; d.samples_per_pixel = 8;
        d.camera.look_from = pt_v3(0, 2, -8); d.camera.look_at = pt_v3(0, 1, 0);
        rc = pt_render_image(s, &d, &img, NULL);
    }
    if (rc == PT_OK)
        for (i = 0; i < 3 * img.width * img.height; i++) sum += img.rgb[i];
    printf("hello: pdftrace %d.%d.%d, render %s, mean %.3f\n", PDFTRACE_VERSION_MAJOR, PDFTRACE_VERSION_MINOR,
           PDFTRACE_VERSION_PATCH, pt_result_string(rc), rc == PT_OK ? sum / (3.0 * img.width * img.height) : 0.0);
    pt_image_free(&img);
    pt_scene_destroy(s);
    return rc == PT_OK && sum > 0 ? 0 : 1;
}
