#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "scene/lexer.h"

static void expect_tok(lexer *lx, token_kind kind, const char *text, int line, int col)
{
    token t;
    hz_error err;
    assert_int_equal(lexer_next(lx, &t, &err), HZ_OK);
    assert_int_equal(t.kind, kind);
    assert_int_equal(t.loc.line, line);
    assert_int_equal(t.loc.column, col);
    if (text) {
        assert_int_equal(t.len, strlen(text));
        assert_memory_equal(t.text, text, t.len);
    }
}

static void test_tokens_and_locations(void **state)
{
    (void)state;
    const char *src = "Shape \"sphere\" # comment \"not a string\"\n"
                      "  \"float radius\" [ 2.5 -1e2 ]\n"
                      "\tLookAt .5 +3\n";
    lexer lx;
    lexer_init(&lx, src, strlen(src), "a.pbrt", NULL);
    expect_tok(&lx, TOK_IDENT, "Shape", 1, 1);
    expect_tok(&lx, TOK_STRING, "sphere", 1, 7);
    expect_tok(&lx, TOK_STRING, "float radius", 2, 3);
    expect_tok(&lx, TOK_LBRACKET, "[", 2, 18);
    token t;
    hz_error err;
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_int_equal(t.kind, TOK_NUMBER);
    assert_true(t.num == 2.5);
    assert_int_equal(t.loc.column, 20);
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_true(t.num == -100.0);
    expect_tok(&lx, TOK_RBRACKET, "]", 2, 29);
    expect_tok(&lx, TOK_IDENT, "LookAt", 3, 2);
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_true(t.num == 0.5);
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_true(t.num == 3.0);
    expect_tok(&lx, TOK_EOF, NULL, 4, 1);
    assert_string_equal(t.loc.file, "a.pbrt");
}

static void test_escapes(void **state)
{
    (void)state;
    const char *src = "\"a\\n\\t\\\\\\\"b\"";
    lexer lx;
    lexer_init(&lx, src, strlen(src), "e", NULL);
    token t;
    hz_error err;
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_int_equal(t.kind, TOK_STRING);
    char *s = token_string_dup(&t);
    assert_string_equal(s, "a\n\t\\\"b");
    free(s);
}

static void expect_error(const char *src, const char *msg)
{
    lexer lx;
    lexer_init(&lx, src, strlen(src), "x.pbrt", NULL);
    token t;
    hz_error err;
    hz_status st;
    do {
        st = lexer_next(&lx, &t, &err);
    } while (st == HZ_OK && t.kind != TOK_EOF);
    assert_int_equal(st, HZ_ERROR);
    if (!strstr(err.message, msg))
        fail_msg("got \"%s\", want \"%s\"", err.message, msg);
}

static void test_errors(void **state)
{
    (void)state;
    expect_error("Shape\n  \"abc", "x.pbrt:2:3: unterminated string");
    expect_error("Shape \"ab\ncd\"", "x.pbrt:1:7: unterminated string");
    expect_error("Shape \"a\\qb\"", "x.pbrt:1:9: unknown escape sequence '\\q'");
    expect_error("\n\n   1.2.3", "x.pbrt:3:4: malformed number '1.2.3'");
    expect_error("-", "x.pbrt:1:1: malformed number '-'");
    expect_error("1e999", "x.pbrt:1:1: number '1e999' is out of range");
    expect_error("0x10", "x.pbrt:1:1: malformed number");
    expect_error("Sha{pe", "x.pbrt:1:4: unexpected character '{'");
    expect_error("ab\x01", "x.pbrt:1:3: unexpected character '?' (byte 0x01)");
    expect_error("\"abc\\", "x.pbrt:1:1: unterminated string");
}

static void test_nul_byte_is_an_error(void **state)
{
    (void)state;
    const char src[] = {'A', ' ', '\0', 'B'};
    lexer lx;
    lexer_init(&lx, src, sizeof src, "n", NULL);
    token t;
    hz_error err;
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_OK);
    assert_int_equal(lexer_next(&lx, &t, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "n:1:3:"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tokens_and_locations),
        cmocka_unit_test(test_escapes),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_nul_byte_is_an_error),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
