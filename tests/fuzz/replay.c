/*
 * replay.c -- runs a fuzz harness of tests/fuzz/ over files, without a fuzzer: the
 * suite builds it with gcc (and ASan + UBSan where they work) beside one harness and
 * replays the committed corpus (tests/test_fuzz_corpus.py).  A broken invariant
 * aborts, a sanitizer reports.
 *
 * Usage: replay FILE...   (prints how many inputs were replayed)
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int main(int argc, char **argv)
{
    int i, n = 0;
    for (i = 1; i < argc; i++) {
        FILE *fp = fopen(argv[i], "rb");
        uint8_t *buf;
        long len;
        if (!fp) {
            fprintf(stderr, "replay: cannot open %s\n", argv[i]);
            return 2;
        }
        fseek(fp, 0, SEEK_END);
        len = ftell(fp);
        fseek(fp, 0, SEEK_SET);
        buf = (uint8_t *)malloc(len > 0 ? (size_t)len : 1);
        if (!buf || (len > 0 && fread(buf, 1, (size_t)len, fp) != (size_t)len)) {
            fprintf(stderr, "replay: cannot read %s\n", argv[i]);
            return 2;
        }
        fclose(fp);
        LLVMFuzzerTestOneInput(buf, (size_t)len);
        free(buf);
        n++;
    }
    printf("replay: %d inputs replayed\n", n);
    return 0;
}
