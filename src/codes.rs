//! Stable diagnostic codes. Codes never change meaning once published; the
//! table [`ALL`] documents each one and the UI tests cover every code.

macro_rules! codes {
    ($($name:ident = $code:literal : $doc:literal;)*) => {
        $(#[doc = $doc] pub const $name: &str = $code;)*
        /// Every code with a one-line description, in order.
        pub const ALL: &[(&str, &str)] = &[$(($code, $doc)),*];
    };
}

codes! {
    E_UNEXPECTED_CHAR = "E0001": "a character that is not part of the language";
    E_UNTERMINATED_STRING = "E0002": "a string literal without its closing quote";
    E_UNTERMINATED_COMMENT = "E0003": "a block comment without its closing `*/`";
    E_BAD_NUMBER = "E0004": "a malformed number literal";
    E_INVALID_UTF8 = "E0005": "bytes that are not valid UTF-8";
    E_TOO_LARGE = "E0006": "a file larger than the limit sdfc reads";
    E_SYNTAX = "E0010": "a syntax error: the parser expected something else";
    E_TOO_DEEP = "E0011": "an expression nested deeper than the limit (brackets, operator and method chains, or `let`s inlined)";
    E_TOO_LARGE_VALUE = "E0012": "a value that, with its `let`s inlined, has more operations than the limit";
    E_UNKNOWN_NAME = "E0100": "a name that is not defined";
    E_DUPLICATE_DEF = "E0101": "a name defined twice";
    E_USED_BEFORE_DEF = "E0102": "a name used before its definition";
    E_UNKNOWN_FUNCTION = "E0103": "a call of a function that does not exist";
    E_UNKNOWN_ARG = "E0104": "a named argument the function does not have";
    E_DUPLICATE_ARG = "E0105": "an argument given twice";
    E_TOO_MANY_ARGS = "E0106": "more positional arguments than the function takes";
    E_MISSING_ARG = "E0107": "a required argument left out";
    E_ARG_ORDER = "E0108": "a positional argument after a named one";
    E_UNKNOWN_FIELD = "E0109": "a field or swizzle the value does not have";
    E_UNKNOWN_SETTING = "E0110": "a setting the block does not have";
    E_DUPLICATE_SETTING = "E0111": "a setting given twice in one block";
    E_DUPLICATE_SEED = "E0112": "a seed declared twice in one atlas";
    E_UNKNOWN_SEED = "E0113": "a merge of a seed the atlas does not declare";
    E_BAD_MERGE = "E0114": "a merge that names fewer than two seeds, or a seed with itself";
    E_NO_SEEDS = "E0115": "an atlas with no seed";
    E_DUPLICATE_RENDER = "E0116": "more than one render item";
    E_TOO_MANY = "E0117": "an atlas with more seeds or merges than the limit";
    E_INLINED_SIZE = "E0118": "a module too large for a driver to build once its calls are inlined (stacked displacements, walks nested inside walks)";
    E_WALK_NESTING = "E0119": "an atlas whose shape costs too much to evaluate (walks nested in walks, stacked displacements and shell maps)";
    E_TYPE_MISMATCH = "E0200": "a value of the wrong type";
    E_BAD_OPERANDS = "E0201": "an operator applied to types it does not accept";
    E_VECTOR_SIZE = "E0202": "a vector of the wrong size, or vectors of different sizes";
    E_NOT_CONSTANT = "E0203": "a surface field where a constant is required";
    E_ATLAS_NOT_SHAPE = "E0204": "an atlas on something that is not a shape";
    E_RENDER_NOT_SHAPE = "E0205": "a render item whose target is not a shape";
    E_DISPLACE_ATLAS = "E0206": "a displacement height read from an atlas on another shape";
    E_DISPLACE_HEIGHT = "E0207": "a displacement height whose slope cannot be bounded (a jump, or an input without a bound)";
    E_NORMAL_MAP_ATLAS = "E0209": "a normal map whose uv does not come from exactly one atlas (its tangent frame is that atlas's)";
    E_RUN_TIME = "E0210": "a run-time parameter where a compile-time constant is required (a setting, a seed, a comparison, or a shape argument parameters cannot set)";
    E_PARAM_RANGE = "E0211": "a malformed `param` item: a default or range that is not constant, no range, a default outside its range, or one parameter too many";
    E_OUT_OF_RANGE = "E0300": "a constant outside the range the parameter accepts";
    E_NOT_POSITIVE = "E0301": "a distance, size or radius that is zero or negative";
    E_NON_FINITE = "E0302": "a constant that is NaN, infinite, or beyond the single-precision (f32) range";
    E_MISSING_FILE = "E0303": "a texture file that does not exist";
    E_IMAGE_FORMAT = "E0304": "a texture file in a format sdfc cannot read";
    E_ZERO_VECTOR = "E0305": "a direction that is the zero vector";
    E_FILE_REFUSED = "E0306": "a file the scene may not read: outside its folder, a folder, a device or FIFO, or too large";
    E_CODEGEN = "E0400": "a scene the code generator cannot compile yet";
    E_SEED_PROJECTION = "E0401": "a seed that cannot be projected onto its atlas's surface";
    E_UNREACHABLE_MERGE = "E0402": "a merge whose seeds cannot reach each other by the geodesic walk";
    E_DERIVED_OVERFLOW = "E0403": "a shape whose derived bounds or Lipschitz bound overflow single precision (long chains of warps)";
    E_UNBOUNDED_STEP = "E0404": "a shape whose step bound depends on a run-time value with no bound over its parameters' ranges (`time` is unbounded)";
    E_INTERNAL = "E0900": "an internal compiler error: naga rejected generated code";
    W_UNUSED = "W0001": "a `let` binding that is never used";
    W_DUPLICATE_MERGE = "W0002": "the same merge edge given twice";
    W_UNUSED_ITEM = "W0003": "a material that is never used";
    W_COINCIDENT_SEEDS = "W0004": "two seeds of one atlas that project to the same point";
    W_OBSTRUCTION = "W0005": "a cycle of merges that cannot close into one uv chart (a topological obstruction)";
    W_SEED_JUMP = "W0006": "a seed that projection moved onto another part of the surface";
    W_TANGENT_PARALLEL = "W0007": "a seed tangent parallel to the surface normal (the default frame is used)";
    W_MIRRORED_SEED = "W0008": "a seed on the mirrored side of an atlas's `mirror` plane (never used)";
    W_NO_REST_POSE = "W0009": "an atlas whose shape the render uses through a warp without an inverse (`elongate`), or in too many places";
    // W0010 (an atlas on a shape that depends on parameters) is retired: such an
    // atlas now follows them (codegen::moving). Its number is not reused.
    N_SEED_MOVED = "N0001": "a seed off the surface, moved onto it (the note gives the distance)";
    N_TRUNCATED = "N0002": "more diagnostics than a file may report; the rest are counted, not shown";
    N_ATLAS_ON_DISPLACED = "N0003": "an atlas on a displaced or shell-mapped shape (it works, at the cost of a walk of the base's atlas per evaluation)";
}
