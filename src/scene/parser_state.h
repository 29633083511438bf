/* The scene parser's state, shared by its files: parser.c (the driver),
 * parser_tokens.c (the token stream), parser_params.c (parameter lists),
 * parser_directives.c and parser_entities.c (what directives do). Each of
 * them includes this rather than another's header, so that they depend on
 * each other one way. The public entry points are scene_parse_file/
 * scene_parse_string in scene_desc.h. */
#ifndef HAZE_SCENE_PARSER_STATE_H
#define HAZE_SCENE_PARSER_STATE_H

#include <stdbool.h>

#include "core/color_space.h"
#include "scene/lexer.h"
#include "scene/scene_desc.h"

enum { ATTR_SHAPE, ATTR_LIGHT, ATTR_MATERIAL, ATTR_MEDIUM, ATTR_TEXTURE, ATTR_COUNT };

/* pbrt-v4's GraphicsState: what AttributeBegin saves and AttributeEnd restores. */
typedef struct {
    transform ctm[2];          /* start and end time */
    unsigned active;           /* ActiveTransform: bit 0 start, bit 1 end */
    bool reverse_orientation;
    int material;
    bool has_area_light;
    scene_entity area_light;   /* owns its params when has_area_light */
    const char *inside, *outside; /* interned medium names */
    param_list attrs[ATTR_COUNT]; /* Attribute defaults */
    color_space color_space;   /* ColorSpace: the space of "rgb" values that follow */
    char kind;                 /* for pushed states: 'a' AttributeBegin, 'o' ObjectBegin */
    file_loc pushed_at;
} gstate;

typedef struct {
    const char *name;
    transform ctm[2];
} named_coordsys;

/* A file being read: its lexer and canonical path (Include cycles). */
typedef struct {
    lexer lx;
    char *canon;
} parser_file;

typedef struct {
    scene_desc *sd;
    gstate gs;
    gstate *stack;
    size_t depth, stack_cap;
    named_coordsys *coords;
    size_t coord_count, coord_cap;
    bool in_world;
    bool warned_transform_begin; /* TransformBegin/End's deprecation, said once */
    file_loc seen_camera, seen_film, seen_sampler, seen_filter, seen_integrator, seen_accelerator;
    long current_object;      /* index being defined, -1 outside ObjectBegin */

    /* One token stream, as pbrt-v4 reads it: Include pushes the included
     * file, whose end pops it and continues the includer's stream, so a
     * directive at the end of an included file takes the parameters that
     * follow the Include. Outermost first; one token of lookahead. */
    parser_file *files;
    size_t file_depth, file_cap;
    token peek;
    bool has_peek;
    bool lex_failed; /* the lexer reported an error: the stream cannot go on */
    /* An allocation failed (parser_oom): the parse ends there rather than going
     * on to the next directive, whose allocations would most likely fail too
     * and bury the cause under a list of consequences. */
    bool out_of_memory;
    /* The name a defining directive (Texture 't', MakeNamedMaterial 'm',
     * MakeNamedMedium 'M') has read: when the directive fails, a stand-in
     * takes the name (parser_define_stand_in), so what refers to it later
     * adds no errors of its own to the report. */
    struct {
        char kind;
        const char *name;
        bool spectrum;
        file_loc loc;
    } defining;
    /* Every included file's text, kept to the end (tokens point into it). */
    char **texts;
    size_t text_count, text_cap;
} parser;

/* Out of memory at `loc`: fills err ("file:line:column: out of memory"),
 * ends the parse (ps->out_of_memory) and returns HZ_ERROR. */
hz_status parser_oom(parser *ps, file_loc loc, hz_error *err);
/* An owned copy of `s` (NULL when out of memory: report it with parser_oom). */
const char *parser_intern(parser *ps, const char *s);
/* Records "FILE:LINE:COL: warning: MESSAGE" in the scene's warnings (printed
 * when it is built). Fails only when out of memory. */
hz_status parser_warn(parser *ps, file_loc at, hz_error *err, const char *fmt, ...) HZ_PRINTF(4, 5);

hz_status parser_need_world(parser *ps, const token *d, const char *name, hz_error *err);
/* `seen` (may be NULL) detects a second Camera, Film... */
hz_status parser_need_options(parser *ps, const token *d, const char *name, file_loc *seen,
                              hz_error *err);
/* Both fail only when out of memory (reported at `at` / `loc`). */
hz_status parser_push_state(parser *ps, char kind, file_loc at, hz_error *err);
void parser_pop_state(parser *ps);
hz_status parser_set_coordsys(parser *ps, const char *name, const transform ctm[2], file_loc loc,
                              hz_error *err);
/* The coordinate system called `name`, NULL when none is. */
named_coordsys *parser_find_coordsys(parser *ps, const char *name);
void parser_state_free(parser *ps);
void gstate_free(gstate *g);

#endif
