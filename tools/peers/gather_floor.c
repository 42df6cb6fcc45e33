/* The least any program can spend resolving the triangles of a binary PLY
 * (float x y z; faces `uchar 3` + three int indices, 13 bytes): the faces
 * read in order, each corner's position gathered from the mapped file with
 * the corners DIST triangles ahead prefetched, on two threads (each half
 * of the faces), and nothing done with the positions but a sum.
 *
 * It is the floor under `mint resample` on a mesh whose vertices are in no
 * spatial order (compare crates/mint-io/examples/gather_floor.rs, mint's
 * own visit path with no work).
 *
 *   cc -O2 -pthread tools/peers/gather_floor.c -o gather_floor
 *   ./gather_floor FILE.ply [DIST] [COPY]
 *
 * DIST defaults to 32. COPY=1 first copies the positions into anonymous
 * memory advised for transparent huge pages (fewer TLB misses), and times
 * the copy apart. Assumes the layout above (as `mint gen` writes it). */
#define _GNU_SOURCE
#include <fcntl.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>

static const uint8_t *faces;
static const char *pos;
static uint64_t nfaces;
static int dist;

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

struct half { uint64_t a, b; double sum; };

static uint32_t corner(uint64_t f, int c) {
    uint32_t v;
    memcpy(&v, faces + f * 13 + 1 + 4 * c, 4);
    return v;
}

static void *run(void *arg) {
    struct half *h = arg;
    double s = 0;
    for (uint64_t i = h->a; i < h->b; i++) {
        if (dist && i + dist < nfaces)
            for (int c = 0; c < 3; c++) __builtin_prefetch(pos + 12ULL * corner(i + dist, c));
        for (int c = 0; c < 3; c++) {
            float q[3];
            memcpy(q, pos + 12ULL * corner(i, c), 12);
            s += q[0] + q[1] + q[2];
        }
    }
    h->sum = s;
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: gather_floor FILE.ply [DIST] [COPY]\n"); return 2; }
    dist = argc > 2 ? atoi(argv[2]) : 32;
    int copy = argc > 3 ? atoi(argv[3]) : 0;
    int fd = open(argv[1], O_RDONLY);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) { perror(argv[1]); return 1; }
    const char *base = mmap(0, st.st_size, PROT_READ, MAP_SHARED, fd, 0);
    if (base == MAP_FAILED) { perror("mmap"); return 1; }
    const char *end = memmem(base, st.st_size < 4096 ? st.st_size : 4096, "end_header\n", 11);
    const char *ev = memmem(base, 4096, "element vertex ", 15), *ef = memmem(base, 4096, "element face ", 13);
    if (!end || !ev || !ef) { fprintf(stderr, "%s: not the expected PLY header\n", argv[1]); return 1; }
    uint64_t nv = strtoull(ev + 15, 0, 10);
    nfaces = strtoull(ef + 13, 0, 10);
    pos = end + 11;
    faces = (const uint8_t *)(pos + 12 * nv);
    if ((const char *)faces + 13 * nfaces > base + st.st_size) { fprintf(stderr, "%s: shorter than its header says\n", argv[1]); return 1; }
    double t0 = now();
    if (copy) {
        size_t huge = 1 << 21;
        char *c = mmap(0, 12 * nv + huge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        c = (char *)(((uintptr_t)c + huge - 1) & ~(uintptr_t)(huge - 1));
        madvise(c, 12 * nv, MADV_HUGEPAGE);
        memcpy(c, pos, 12 * nv);
        pos = c;
    }
    double t1 = now();
    pthread_t th[2];
    struct half h[2] = {{0, nfaces / 2, 0}, {nfaces / 2, nfaces, 0}};
    for (int t = 0; t < 2; t++) pthread_create(&th[t], 0, run, &h[t]);
    for (int t = 0; t < 2; t++) pthread_join(th[t], 0);
    printf("%s: %lu faces, dist %d, copy %d: copy %.2f s, gather %.2f s (check %g)\n", argv[1], (unsigned long)nfaces, dist, copy, t1 - t0, now() - t1, h[0].sum + h[1].sum);
    return 0;
}
