# conf2man.awk - trajd.conf(5) from config/trajd.conf, so the manual page
# cannot drift from the commented example file (the one source).
#   awk -v version=0.1 -f daemon/doc/conf2man.awk config/trajd.conf > trajd.conf.5
# Reading rules (the file's own conventions, see its header):
#   [section]                  -> .SS; [object.boat] is shown as [object.NAME]
#   "# ---- title ----"        -> .SS title
#   "#key = value"             -> the key with its default; "key = value" -> the
#                                 key as the example sets it; consecutive keys
#                                 share the comment lines just before them
#   "# text"                   -> the description of the keys that follow, or a
#                                 paragraph; "#  indented" lines keep their layout
# The header block (before the first section) becomes DESCRIPTION.
function esc(s) {
    gsub(/\\/, "\\e", s)
    gsub(/-/, "\\-", s)
    gsub(/,/, ",\\:", s)       # a break point after a comma: long column lists
    if (s ~ /^[.']/) s = "\\&" s
    return s
}
function flush(   i) {
    if (nkeys > 0) {
        print ".TP"
        for (i = 1; i <= nkeys; i++) {
            if (i > 1) print ".TQ"
            print keys[i]
        }
        if (ntext == 0) print "(no description)"
    } else if (ntext > 0) {
        print ".PP"
    }
    for (i = 1; i <= ntext; i++) print text[i]
    nkeys = 0; ntext = 0; indented = 0
}
function addtext(s) {
    if (s ~ /^ /) { text[++ntext] = ".br"; sub(/^ +/, "", s); text[++ntext] = "\\ \\ \\ \\ " esc(s); indented = 1; return }
    if (s ~ /^[a-z0-9_|]+: / || indented) text[++ntext] = ".br"
    indented = 0
    text[++ntext] = esc(s)
}
BEGIN {
    nkeys = 0; ntext = 0; insec = 0
    print ".\\\" Generated from config/trajd.conf by daemon/doc/conf2man.awk: edit those, not this."
    print ".TH TRAJD.CONF 5 \"\" \"trajd " version "\" \"File Formats\""
    print ".ad l"
    print ".SH NAME"
    print "trajd.conf \\- trajd configuration file"
    print ".SH SYNOPSIS"
    print "/etc/trajd/trajd.conf"
    print ".SH DESCRIPTION"
}
NR == 1 { next }                                   # "# /etc/trajd/trajd.conf - ..." is NAME
/^[ \t]*$/ { flush(); next }
/^\[/ {
    if (!insec) { flush(); print ".SH SECTIONS AND KEYS"; insec = 1 }
    name = $0; sub(/^\[object\.[^]]*\]/, "[object.NAME]", name)
    # comment lines just above a section introduce it
    keep = ntext; for (i = 1; i <= ntext; i++) saved[i] = text[i]
    nkeys = 0; ntext = 0
    print ".SS \"" esc(name) "\""
    if (keep > 0) { print ".PP"; for (i = 1; i <= keep; i++) print saved[i] }
    next
}
/^# ---- .* ----$/ {
    flush(); t = $0; sub(/^# ---- /, "", t); sub(/ ----$/, "", t)
    print ".SS \"" esc(t) "\""; next
}
/^#[a-z][a-z0-9_.]* =/ || /^[a-z][a-z0-9_.]* =/ {
    line = $0; dflt = (line ~ /^#/); sub(/^#/, "", line)
    k = line; sub(/ =.*/, "", k); v = line; sub(/^[^=]*= ?/, "", v)
    if (ntext > 0 && nkeys == 0) { } else if (ntext > 0) flush()
    keys[++nkeys] = "\\fB" esc(k) "\\fR = \\fI" (v == "" ? "(empty)" : esc(v)) "\\fR" \
        (dflt ? " (default)" : " (as the shipped example sets it)")
    next
}
/^[#;]/ {
    if (nkeys > 0) flush()
    s = $0; sub(/^[#;] ?/, "", s)
    if (s == "") { flush(); next }
    addtext(s); next
}
{ flush(); print ".\\\" unrecognised line " NR " of config/trajd.conf"; bad = 1 }
END {
    flush()
    print ".SH FILES"
    print "/etc/trajd/trajd.conf; the example it is made from: config/trajd.conf in the source."
    print ".SH SEE ALSO"
    print ".BR trajd (8),"
    print ".BR trajreplay (1)"
    if (bad) exit 1
}
