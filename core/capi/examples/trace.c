/* A C program using raypipe-core through its C API, as C firmware would: load a scene
 * image into an aligned buffer, parse it once, trace the eye rays of a 32 x 32 view one
 * by one and as packets, check every hit against brute force and the any-hit query,
 * read each hit's geometric normal, material and object, shade, and check that
 * corrupted images and null arguments are refused with a status that names the cause.
 *
 *   cc -O2 -I core/capi/include core/capi/examples/trace.c \
 *      core/capi/target/release/libraypipe_capi.a -o trace && ./trace fixtures/tetra-bvh4.rpsi
 *
 * Exit status 0 when every check holds. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "raypipe.h"

static int same(const RpHit *a, const RpHit *b) { return memcmp(a, b, sizeof *a) == 0; }

int main(int argc, char **argv) {
    const char *path = argc > 1 ? argv[1] : "fixtures/tetra-bvh4.rpsi";
    FILE *f = fopen(path, "rb");
    if (!f) { fprintf(stderr, "%s: cannot open\n", path); return 2; }
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    /* parse needs a 16-byte aligned image (64 is a cache line). */
    unsigned char *image = aligned_alloc(64, ((size_t)len + 63) / 64 * 64);
    if (!image || fread(image, 1, (size_t)len, f) != (size_t)len) { fprintf(stderr, "%s: cannot read\n", path); return 2; }
    fclose(f);

    RpScene scene;
    int code = rp_scene_parse(image, (size_t)len, &scene);
    if (code != RP_OK) { fprintf(stderr, "%s: %s\n", path, rp_status_string(code)); return 3; }
    uint32_t cam_w, cam_h;
    if (rp_camera_size(&scene, &cam_w, &cam_h) != RP_OK || cam_w == 0 || cam_h == 0) { fprintf(stderr, "no camera size\n"); return 4; }
    if (rp_version() != 0x000100 || strcmp(rp_version_string(), "0.1.0") != 0) { fprintf(stderr, "version %s\n", rp_version_string()); return 4; }

    enum { W = 32, H = 32 };
    RpRay rays[W * H];
    RpHit hits[W * H];
    int hit_count = 0;
    for (uint32_t y = 0; y < H; y++) {
        for (uint32_t x = 0; x < W; x++) {
            RpRay *r = &rays[y * W + x];
            if (rp_camera_ray(&scene, x, y, W, H, r) != RP_OK) { fprintf(stderr, "no camera ray\n"); return 4; }
            RpHit hit, reference;
            bool a = rp_trace(&scene, r, &hit);
            bool b = rp_trace_brute_force(&scene, r, &reference);
            if (a != b || (a && !same(&hit, &reference))) { fprintf(stderr, "pixel %u,%u: walk and brute force differ\n", x, y); return 5; }
            if (rp_occluded(&scene, r) != a) { fprintf(stderr, "pixel %u,%u: any-hit differs\n", x, y); return 5; }
            RpRgb bg = {0.1f, 0.2f, 0.3f}, rgb;
            if (rp_shade(&scene, r, a ? &hit : NULL, bg, &rgb) != RP_OK || !(rgb.r >= 0.0f)) { fprintf(stderr, "shade failed\n"); return 6; }
            if (a) {
                /* The geometric normal faces the eye or away, never along the ray's side. */
                float along = hit.ng[0] * r->dir[0] + hit.ng[1] * r->dir[1] + hit.ng[2] * r->dir[2];
                float len2 = hit.ng[0] * hit.ng[0] + hit.ng[1] * hit.ng[1] + hit.ng[2] * hit.ng[2];
                if (!(len2 > 0.0f) || along == 0.0f || hit.material == RP_NO_MATERIAL) { fprintf(stderr, "pixel %u,%u: hit without normal or material\n", x, y); return 6; }
            }
            if (a) hits[y * W + x] = hit;
            hit_count += a;
        }
    }
    /* The same rays as packets of up to 64 (16 lanes sharing one walk). */
    for (int i = 0; i < W * H; i += 64) {
        RpHit packet_hits[64];
        uint64_t mask = rp_trace_packet(&scene, &rays[i], 64, packet_hits);
        for (int k = 0; k < 64; k++) {
            RpHit single;
            bool a = rp_trace(&scene, &rays[i + k], &single);
            bool b = (mask >> k) & 1;
            if (a != b || (a && !same(&packet_hits[k], &hits[i + k]))) { fprintf(stderr, "ray %d: packet differs\n", i + k); return 7; }
        }
    }
    if (hit_count == 0 || hit_count == W * H) { fprintf(stderr, "implausible: %d hits\n", hit_count); return 8; }

    /* Refusals: a flipped byte is a checksum error, null arguments are argument errors. */
    image[len / 2] ^= 0x40;
    RpScene bad;
    code = rp_scene_parse(image, (size_t)len, &bad);
    if (code != RP_ERR_CHECKSUM || strstr(rp_status_string(code), "checksum") == NULL) { fprintf(stderr, "corruption accepted\n"); return 9; }
    if (strcmp(rp_status_string(12345), "unknown status code") != 0) { fprintf(stderr, "unknown code named\n"); return 9; }
    image[len / 2] ^= 0x40;
    if (rp_scene_parse(NULL, 0, &bad) != RP_ERR_ARGUMENT || rp_trace(NULL, &rays[0], &hits[0])) { fprintf(stderr, "null accepted\n"); return 9; }
    if (rp_scene_parse(image + 1, (size_t)len - 1, &bad) == RP_OK) { fprintf(stderr, "misaligned accepted\n"); return 9; }

    printf("%s: %u triangles, %d of %d rays hit; walk, brute force, any-hit, packets agree (raypipe %s): ok\n",
           path, rp_triangle_count(&scene), hit_count, W * H, rp_version_string());
    free(image);
    return 0;
}
