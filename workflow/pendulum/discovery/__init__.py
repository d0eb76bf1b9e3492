"""Discovery: a baseline fit's residuals in, the missing effect named (or honestly not) out, with the evidence."""
