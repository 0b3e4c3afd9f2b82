"""A small JSON Schema checker, enough for the schemas in vectors/schema/ (stdlib only).

It knows: type, enum, const, properties, required, additionalProperties, items, minItems,
minimum, maximum, pattern, oneOf and local $ref (#/$defs/...). A schema that uses any other
keyword is refused, so a schema cannot silently check less than it says."""

import re

KNOWN = {
    "$schema", "$id", "$defs", "title", "description", "type", "enum", "const", "properties", "required",
    "additionalProperties", "items", "minItems", "minimum", "maximum", "pattern", "oneOf", "$ref",
}


class SchemaError(Exception):
    """A value that does not follow its schema, or a schema this checker cannot read."""


def _type_ok(value, t):
    if t == "object":
        return isinstance(value, dict)
    if t == "array":
        return isinstance(value, list)
    if t == "string":
        return isinstance(value, str)
    if t == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    if t == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if t == "boolean":
        return isinstance(value, bool)
    if t == "null":
        return value is None
    raise SchemaError("unknown type `%s` in a schema" % t)


def _pattern_matches(pattern, value):
    """JSON Schema's `pattern` (ECMA-262, unanchored): `$` is the end of the string. Python's
    `$` also matches before a final newline, so "aaa...a\\n" would pass `^[0-9a-f]{64}$`; an
    unescaped `$` becomes `\\Z` here."""
    return re.search(re.sub(r"(?<!\\)\$", r"\\Z", pattern), value) is not None


def errors(value, schema, root=None, path="$"):
    """Every way `value` breaks `schema`, as messages with a path."""
    root = schema if root is None else root
    unknown = set(schema) - KNOWN
    if unknown:
        raise SchemaError("this checker does not know the keywords %s" % sorted(unknown))
    if "$ref" in schema:
        ref = schema["$ref"]
        if not ref.startswith("#/$defs/"):
            raise SchemaError("only local #/$defs/ references are supported: %s" % ref)
        return errors(value, root["$defs"][ref[len("#/$defs/"):]], root, path)
    out = []
    if "type" in schema:
        types = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        if not any(_type_ok(value, t) for t in types):
            return ["%s: expected %s, got %r" % (path, " or ".join(types), value)]
    if "const" in schema and value != schema["const"]:
        out.append("%s: expected %r" % (path, schema["const"]))
    if "enum" in schema and value not in schema["enum"]:
        out.append("%s: %r is not one of %r" % (path, value, schema["enum"]))
    if isinstance(value, str) and "pattern" in schema and not _pattern_matches(schema["pattern"], value):
        out.append("%s: %r does not match %s" % (path, value, schema["pattern"]))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if "minimum" in schema and value < schema["minimum"]:
            out.append("%s: %r is below %r" % (path, value, schema["minimum"]))
        if "maximum" in schema and value > schema["maximum"]:
            out.append("%s: %r is above %r" % (path, value, schema["maximum"]))
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0):
            out.append("%s: fewer than %d items" % (path, schema["minItems"]))
        if "items" in schema:
            for i, v in enumerate(value):
                out.extend(errors(v, schema["items"], root, "%s[%d]" % (path, i)))
    if isinstance(value, dict):
        props = schema.get("properties", {})
        for k in schema.get("required", []):
            if k not in value:
                out.append("%s: missing `%s`" % (path, k))
        extra = schema.get("additionalProperties", True)
        for k, v in value.items():
            p = "%s.%s" % (path, k)
            if k in props:
                out.extend(errors(v, props[k], root, p))
            elif extra is False:
                out.append("%s: unexpected key" % p)
            elif isinstance(extra, dict):
                out.extend(errors(v, extra, root, p))
    if "oneOf" in schema:
        fits = [not errors(value, s, root, path) for s in schema["oneOf"]]
        if fits.count(True) != 1:
            out.append("%s: matches %d of the oneOf alternatives, not exactly one" % (path, fits.count(True)))
    return out


def validate(value, schema):
    """Raises SchemaError with the first few problems when `value` breaks `schema`."""
    errs = errors(value, schema)
    if errs:
        raise SchemaError("; ".join(errs[:5]) + (" (and %d more)" % (len(errs) - 5) if len(errs) > 5 else ""))
