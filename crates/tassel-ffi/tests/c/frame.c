/* A C client of Tassel's ABI, run by tests/c_abi.rs.
 *
 *   frame FILE MODE FRAMES DT AMP FREQ
 *
 * Loads FILE (its bytes, with no rig: its VRM spring bones), moves the character's root
 * along x by AMP * sin(2 pi FREQ t) (tassel simulate's `--motion sin`), feeds the rest pose
 * as the animation every frame, and prints each joint's world position per frame,
 * "P frame joint x y z", composing the output locals itself. Also checks, printing
 * "FAIL ..." and exiting 1 on a broken promise: NULL and wrong lengths are errors with a
 * message; a NaN frame is an error that changes nothing; the same buffer in and out gives
 * the bits of two buffers. */
#include "tassel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define F 10

static int failures = 0;

static void fail(const char *what) {
  const char *e = tassel_last_error();
  printf("FAIL %s (last error: %s)\n", what, e ? e : "none");
  failures++;
}

/* a * b for transforms (translation, unit quaternion, scale), in double. */
typedef struct { double t[3], q[4], s[3]; } Xf;

static void rotate(const double q[4], const double v[3], double out[3]) {
  /* v + 2 w (u x v) + 2 u x (u x v) */
  double ux = q[0], uy = q[1], uz = q[2], w = q[3];
  double cx = uy * v[2] - uz * v[1], cy = uz * v[0] - ux * v[2], cz = ux * v[1] - uy * v[0];
  double ccx = uy * cz - uz * cy, ccy = uz * cx - ux * cz, ccz = ux * cy - uy * cx;
  out[0] = v[0] + 2 * (w * cx + ccx);
  out[1] = v[1] + 2 * (w * cy + ccy);
  out[2] = v[2] + 2 * (w * cz + ccz);
}

static Xf compose(const Xf *a, const Xf *b) {
  Xf r;
  double scaled[3] = {a->s[0] * b->t[0], a->s[1] * b->t[1], a->s[2] * b->t[2]};
  double turned[3];
  rotate(a->q, scaled, turned);
  for (int i = 0; i < 3; i++) r.t[i] = a->t[i] + turned[i];
  const double *p = a->q, *q = b->q;
  r.q[0] = p[3] * q[0] + p[0] * q[3] + p[1] * q[2] - p[2] * q[1];
  r.q[1] = p[3] * q[1] - p[0] * q[2] + p[1] * q[3] + p[2] * q[0];
  r.q[2] = p[3] * q[2] + p[0] * q[1] - p[1] * q[0] + p[2] * q[3];
  r.q[3] = p[3] * q[3] - p[0] * q[0] - p[1] * q[1] - p[2] * q[2];
  for (int i = 0; i < 3; i++) r.s[i] = a->s[i] * b->s[i];
  return r;
}

static Xf from_floats(const float *v) {
  Xf x;
  for (int i = 0; i < 3; i++) x.t[i] = v[i];
  for (int i = 0; i < 4; i++) x.q[i] = v[3 + i];
  for (int i = 0; i < 3; i++) x.s[i] = v[7 + i];
  return x;
}

/* World transform of joint j (memoised: glTF may list a child before its parent). */
static Xf world_of(const TasselCharacter *c, size_t j, const Xf *root, const float *locals,
                   Xf *world, char *done) {
  if (done[j]) return world[j];
  Xf local = from_floats(locals + j * F);
  int32_t p = tassel_joint_parent(c, j);
  Xf parent = p < 0 ? *root : world_of(c, (size_t)p, root, locals, world, done);
  world[j] = compose(&parent, &local);
  done[j] = 1;
  return world[j];
}

static unsigned char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *bytes = malloc((size_t)n);
  if (fread(bytes, 1, (size_t)n, f) != (size_t)n) n = -1;
  fclose(f);
  *len = (size_t)n;
  return n < 0 ? NULL : bytes;
}

int main(int argc, char **argv) {
  if (argc != 7) {
    fprintf(stderr, "usage: frame FILE MODE FRAMES DT AMP FREQ\n");
    return 2;
  }
  size_t len;
  unsigned char *bytes = read_file(argv[1], &len);
  if (!bytes) {
    fprintf(stderr, "cannot read %s\n", argv[1]);
    return 2;
  }
  const char *mode = argv[2];
  int frames = atoi(argv[3]);
  float dt = (float)atof(argv[4]), amp = (float)atof(argv[5]), freq = (float)atof(argv[6]);

  /* Bad input first: each an error with a message, none a crash. */
  if (tassel_last_error() != NULL) fail("an error before any call");
  if (tassel_character_load(NULL, 10, NULL, NULL) != NULL) fail("load(NULL) gave a character");
  if (tassel_last_error() == NULL || !strstr(tassel_last_error(), "NULL")) fail("load(NULL) says nothing of NULL");
  if (tassel_character_load(bytes, len / 2, NULL, NULL) != NULL) fail("half a file loaded");
  if (tassel_character_load(bytes, len, NULL, "sideways") != NULL) fail("mode 'sideways' loaded");
  if (!strstr(tassel_last_error(), "sideways")) fail("the bad mode is not named");
  if (tassel_joint_count(NULL) != 0) fail("joint_count(NULL)");
  if (tassel_frame(NULL, NULL, NULL, NULL, 0, 0.0f) != -1) fail("frame(NULL)");

  /* Three characters of the same file: a (two buffers), b (in place), c (a NaN frame and
     a wrong length among its frames). All three must end with the same bits. */
  TasselCharacter *a = tassel_character_load(bytes, len, NULL, mode);
  TasselCharacter *b = tassel_character_load(bytes, len, NULL, mode);
  TasselCharacter *c = tassel_character_load(bytes, len, NULL, mode);
  free(bytes);
  if (!a || !b || !c) {
    fail("load");
    return 1;
  }
  if (strcmp(tassel_mode(a), mode) != 0) fail("the mode is not the one asked for");
  size_t n = tassel_joint_count(a);
  size_t floats = n * F;
  float *rest = malloc(floats * sizeof(float));
  float *out_a = malloc(floats * sizeof(float));
  float *buf_b = malloc(floats * sizeof(float));
  float *out_c = malloc(floats * sizeof(float));
  float *bad = malloc(floats * sizeof(float));
  Xf *world = malloc(n * sizeof(Xf));
  char *done = malloc(n);
  if (tassel_rest_locals(a, rest, floats) != 0) fail("rest_locals");
  if (tassel_rest_locals(a, rest, floats - 1) != -1) fail("rest_locals with a short buffer");
  if (tassel_joint_name(a, n) != NULL) fail("a name past the last joint");
  if (tassel_joint_parent(a, n) != -2) fail("a parent past the last joint");
  printf("J %zu\n", n);
  for (size_t j = 0; j < n; j++) printf("N %zu %d %s\n", j, tassel_joint_parent(a, j), tassel_joint_name(a, j));

  for (int f = 1; f <= frames; f++) {
    float t = (float)f * dt;
    float w = 6.28318530717958647692f * freq * t;
    float root[F] = {amp * sinf(w), 0, 0, 0, 0, 0, 1, 1, 1, 1};
    if (tassel_frame(a, root, rest, out_a, floats, dt) != 0) fail("frame a");
    memcpy(buf_b, rest, floats * sizeof(float));
    if (tassel_frame(b, root, buf_b, buf_b, floats, dt) != 0) fail("frame b in place");
    if (f == frames / 2) {
      /* A NaN in a joint's rotation and a short buffer: errors, nothing changes. */
      memcpy(bad, rest, floats * sizeof(float));
      bad[(n - 1) * F + 4] = NAN;
      for (size_t i = 0; i < floats; i++) out_c[i] = -7.0f;
      if (tassel_frame(c, root, bad, out_c, floats, dt) != -1) fail("a NaN frame passed");
      if (!strstr(tassel_last_error(), "not finite")) fail("the NaN frame's message");
      if (tassel_frame(c, root, rest, out_c, floats - F, dt) != -1) fail("a short frame passed");
      if (tassel_frame(c, root, rest, rest + F, floats, dt) != -1) fail("overlapping buffers passed");
      for (size_t i = 0; i < floats; i++)
        if (out_c[i] != -7.0f) { fail("a failed frame wrote its output"); break; }
    }
    if (tassel_frame(c, root, rest, out_c, floats, dt) != 0) fail("frame c");
    if (memcmp(out_a, buf_b, floats * sizeof(float)) != 0) fail("in place differs from two buffers");
    if (memcmp(out_a, out_c, floats * sizeof(float)) != 0) fail("a failed frame changed the character");

    Xf r = from_floats(root);
    memset(done, 0, n);
    for (size_t j = 0; j < n; j++) {
      Xf x = world_of(a, j, &r, out_a, world, done);
      printf("P %d %zu %.9g %.9g %.9g\n", f, j, x.t[0], x.t[1], x.t[2]);
    }
  }
  tassel_character_free(a);
  tassel_character_free(b);
  tassel_character_free(c);
  tassel_character_free(NULL);
  free(rest), free(out_a), free(buf_b), free(out_c), free(bad), free(world), free(done);
  printf("DONE %d\n", failures);
  return failures ? 1 : 0;
}
