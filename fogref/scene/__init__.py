"""The scene XML read once: parse, ``$default``s, vocabulary, inputs, description, writer, edits."""
