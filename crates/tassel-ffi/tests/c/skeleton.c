/* A C client of tassel_character_new, run by tests/c_abi.rs.

     skeleton FILE SPRINGS_JSON MODE FRAMES

   Loads FILE's bytes with tassel_character_load, takes the joints' names, parents and rest
   pose it reports, reads SPRINGS_JSON (the file's own VRMC_springBone or secondaryAnimation,
   cut out by the test) and makes a second character with tassel_character_new from them.
   Both step FRAMES frames of a swaying root with one read joint turning; their outputs
   must be the same bytes ("SAME <frames>"), and a skeleton with a cycle must be refused
   with a message. Exit 0 when all holds. */
#include "tassel.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *buf = malloc((size_t)n + 1);
  if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
    fclose(f);
    free(buf);
    return NULL;
  }
  fclose(f);
  buf[n] = 0;
  *len = (size_t)n;
  return buf;
}

int main(int argc, char **argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: skeleton FILE SPRINGS_JSON MODE FRAMES\n");
    return 2;
  }
  size_t len = 0, json_len = 0;
  char *bytes = slurp(argv[1], &len);
  char *springs = slurp(argv[2], &json_len);
  if (!bytes || !springs) {
    fprintf(stderr, "cannot read the inputs\n");
    return 2;
  }
  const char *mode = argv[3];
  int frames = atoi(argv[4]);
  TasselCharacter *a = tassel_character_load((const uint8_t *)bytes, len, NULL, mode);
  if (!a) {
    printf("FAIL load: %s\n", tassel_last_error());
    return 1;
  }
  size_t n = tassel_joint_count(a);
  const char **names = malloc(n * sizeof *names);
  int32_t *parents = malloc(n * sizeof *parents);
  float *rest = malloc(n * 10 * sizeof *rest);
  float *in = malloc(n * 10 * sizeof *in);
  float *out_a = malloc(n * 10 * sizeof *out_a);
  float *out_b = malloc(n * 10 * sizeof *out_b);
  for (size_t j = 0; j < n; j++) {
    names[j] = tassel_joint_name(a, j);
    parents[j] = tassel_joint_parent(a, j);
  }
  if (tassel_rest_locals(a, rest, n * 10) != 0) {
    printf("FAIL rest: %s\n", tassel_last_error());
    return 1;
  }
  TasselCharacter *b = tassel_character_new(names, parents, rest, n, NULL, springs, mode);
  if (!b) {
    printf("FAIL new: %s\n", tassel_last_error());
    return 1;
  }
  size_t turn = 0;
  if (tassel_read_joint_count(a) > 0) {
    size_t *read = malloc(tassel_read_joint_count(a) * sizeof *read);
    tassel_read_joints(a, read, tassel_read_joint_count(a));
    turn = read[0];
    free(read);
  }
  for (int f = 0; f < frames; f++) {
    float t = (float)f / 60.0f;
    float root[10] = {0.3f * sinf(2.0f * t), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f, 1.0f};
    memcpy(in, rest, n * 10 * sizeof *in);
    in[turn * 10 + 3] = sinf(0.3f * sinf(3.0f * t));
    in[turn * 10 + 6] = cosf(0.3f * sinf(3.0f * t));
    float dt = f == frames / 2 ? 0.2f : 1.0f / 60.0f;
    int ra = tassel_frame(a, root, in, out_a, n * 10, dt);
    int rb = tassel_frame(b, root, in, out_b, n * 10, dt);
    if (ra != 0 || rb != 0 || memcmp(out_a, out_b, n * 10 * sizeof *out_a) != 0) {
      printf("FAIL frame %d differs (%d %d)\n", f, ra, rb);
      return 1;
    }
  }
  /* A cycle through joints 0 and 1 (when there are two): refused, with a message. */
  if (n >= 2) {
    int32_t p0 = parents[0], p1 = parents[1];
    parents[0] = 1;
    parents[1] = 0;
    TasselCharacter *bad = tassel_character_new(names, parents, rest, n, NULL, springs, mode);
    if (bad || !tassel_last_error() || !strstr(tassel_last_error(), "cycle")) {
      printf("FAIL a cycle was taken\n");
      return 1;
    }
    parents[0] = p0;
    parents[1] = p1;
  }
  printf("SAME %d\n", frames);
  tassel_character_free(a);
  tassel_character_free(b);
  free(names), free(parents), free(rest), free(in), free(out_a), free(out_b);
  free(bytes), free(springs);
  return 0;
}
