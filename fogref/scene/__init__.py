"""The scene XML read once: parse, ``$default``s, vocabulary and ranges, inputs, description, writer, edits."""
