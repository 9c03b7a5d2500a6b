// A small strict JSON reader and writer for the patch protocol (vr-workbench-patch/1).
//
// Plain C# (.NET Framework 4.x, C# 7.2), no UnityEngine, no external library:
// the protocol core runs in Unity and, unchanged, under mono in the workbench's tests.
//
// Reader: RFC 8259 exactly (no comments, no trailing commas, no NaN/Infinity, no
// single quotes, no leading zeros, no control characters in strings), objects keep
// their key order (an unknown field is named in the order the client sent it), a
// key given twice is refused, nesting is limited to MaxDepth.
// Values: JsonObject (ordered pairs), List<object>, string, JsonNumber, bool, null.
//
// Writer: the same spacing as the workbench's Python side (", " and ": "), non-ASCII
// and control characters escaped as \uXXXX (lower-case hex), as Python's json.dumps
// writes them, so the C# server's replies are byte for byte the reference server's.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Text;

namespace VrColourWorkbench.Patch
{
    /// <summary>A JSON syntax error, with the position (in characters) where it was found.</summary>
    public sealed class PatchJsonException : Exception
    {
        public PatchJsonException(string message) : base(message) { }
    }

    /// <summary>A JSON number as written (its text is kept so that it can be echoed unchanged).</summary>
    public sealed class JsonNumber
    {
        public readonly string Text;
        public readonly double Value;

        public JsonNumber(string text, double value) { Text = text; Value = value; }

        /// <summary>Written without a fraction or an exponent (JSON's integer form).</summary>
        public bool IsIntegerLiteral
        {
            get { return Text.IndexOf('.') < 0 && Text.IndexOf('e') < 0 && Text.IndexOf('E') < 0; }
        }

        public override string ToString() { return Text; }
    }

    /// <summary>A JSON object: its members in the order they were written.</summary>
    public sealed class JsonObject
    {
        readonly List<KeyValuePair<string, object>> members = new List<KeyValuePair<string, object>>();

        public int Count { get { return members.Count; } }
        public IEnumerable<KeyValuePair<string, object>> Members { get { return members; } }

        public bool Has(string key)
        {
            foreach (var member in members) if (member.Key == key) return true;
            return false;
        }

        public bool TryGet(string key, out object value)
        {
            foreach (var member in members)
            {
                if (member.Key == key) { value = member.Value; return true; }
            }
            value = null;
            return false;
        }

        public object Get(string key) { object value; TryGet(key, out value); return value; }

        /// <summary>Appends a member (a writer's object; the reader refuses duplicate keys before this).</summary>
        public JsonObject Add(string key, object value)
        {
            members.Add(new KeyValuePair<string, object>(key, value));
            return this;
        }
    }

    /// <summary>Strict JSON text to values, and values to JSON text.</summary>
    public static class PatchJson
    {
        /// <summary>Deepest nesting of arrays and objects accepted (a request is flat).</summary>
        public const int MaxDepth = 32;

        /// <summary>Parses one JSON text (whitespace around it allowed).</summary>
        /// <exception cref="PatchJsonException">Not exactly one valid JSON value.</exception>
        public static object Parse(string text)
        {
            var reader = new Reader(text);
            reader.SkipWhitespace();
            object value = reader.ReadValue(0);
            reader.SkipWhitespace();
            if (!reader.AtEnd) throw reader.Error("extra data after the JSON value");
            return value;
        }

        /// <summary>One value as JSON text, with Python's json.dumps spacing (", " and ": ").</summary>
        public static string Write(object value)
        {
            var builder = new StringBuilder();
            WriteValue(builder, value);
            return builder.ToString();
        }

        static void WriteValue(StringBuilder builder, object value)
        {
            if (value == null) { builder.Append("null"); return; }
            if (value is bool) { builder.Append((bool)value ? "true" : "false"); return; }
            var text = value as string;
            if (text != null) { WriteString(builder, text); return; }
            var number = value as JsonNumber;
            if (number != null) { builder.Append(number.Text); return; }
            if (value is int || value is long)
            {
                builder.Append(Convert.ToInt64(value).ToString(CultureInfo.InvariantCulture));
                return;
            }
            if (value is double || value is float)
            {
                double real = Convert.ToDouble(value);
                string written = real.ToString("R", CultureInfo.InvariantCulture);
                // Python writes an integral float as "1.0": so do we, for the same records
                if (!double.IsInfinity(real) && !double.IsNaN(real) && written.IndexOfAny(new[] { '.', 'E', 'e' }) < 0)
                    written += ".0";
                builder.Append(written);
                return;
            }
            var obj = value as JsonObject;
            if (obj != null)
            {
                builder.Append('{');
                bool first = true;
                foreach (var member in obj.Members)
                {
                    if (!first) builder.Append(", ");
                    first = false;
                    WriteString(builder, member.Key);
                    builder.Append(": ");
                    WriteValue(builder, member.Value);
                }
                builder.Append('}');
                return;
            }
            var list = value as System.Collections.IList;
            if (list != null)
            {
                builder.Append('[');
                for (int i = 0; i < list.Count; i++)
                {
                    if (i > 0) builder.Append(", ");
                    WriteValue(builder, list[i]);
                }
                builder.Append(']');
                return;
            }
            throw new ArgumentException("cannot write a " + value.GetType().Name + " as JSON");
        }

        /// <summary>A JSON string literal, escaped as Python's json.dumps (ensure_ascii) escapes it.</summary>
        public static void WriteString(StringBuilder builder, string text)
        {
            builder.Append('"');
            foreach (char c in text)
            {
                switch (c)
                {
                    case '"': builder.Append("\\\""); break;
                    case '\\': builder.Append("\\\\"); break;
                    case '\n': builder.Append("\\n"); break;
                    case '\r': builder.Append("\\r"); break;
                    case '\t': builder.Append("\\t"); break;
                    case '\b': builder.Append("\\b"); break;
                    case '\f': builder.Append("\\f"); break;
                    default:
                        if (c < 0x20 || c > 0x7e)
                            builder.Append("\\u").Append(((int)c).ToString("x4", CultureInfo.InvariantCulture));
                        else
                            builder.Append(c);
                        break;
                }
            }
            builder.Append('"');
        }

        sealed class Reader
        {
            readonly string text;
            int position;

            public Reader(string text) { this.text = text; }

            public bool AtEnd { get { return position >= text.Length; } }

            public PatchJsonException Error(string what)
            {
                return new PatchJsonException(what + " at character " + position.ToString(CultureInfo.InvariantCulture));
            }

            public void SkipWhitespace()
            {
                while (position < text.Length)
                {
                    char c = text[position];
                    if (c != ' ' && c != '\t' && c != '\n' && c != '\r') return;
                    position++;
                }
            }

            public object ReadValue(int depth)
            {
                if (AtEnd) throw Error("expected a value");
                char c = text[position];
                switch (c)
                {
                    case '{': return ReadObject(depth + 1);
                    case '[': return ReadArray(depth + 1);
                    case '"': return ReadString();
                    case 't': ReadLiteral("true"); return true;
                    case 'f': ReadLiteral("false"); return false;
                    case 'n': ReadLiteral("null"); return null;
                    default:
                        if (c == '-' || (c >= '0' && c <= '9')) return ReadNumber();
                        throw Error("expected a value");
                }
            }

            void ReadLiteral(string literal)
            {
                if (string.CompareOrdinal(text, position, literal, 0, literal.Length) != 0) throw Error("expected a value");
                position += literal.Length;
            }

            JsonObject ReadObject(int depth)
            {
                if (depth > MaxDepth) throw Error("nested deeper than " + MaxDepth);
                var result = new JsonObject();
                position++;  // {
                SkipWhitespace();
                if (!AtEnd && text[position] == '}') { position++; return result; }
                while (true)
                {
                    SkipWhitespace();
                    if (AtEnd || text[position] != '"') throw Error("expected a member name in double quotes");
                    string key = ReadString();
                    if (result.Has(key)) throw Error("member '" + key + "' given twice");
                    SkipWhitespace();
                    if (AtEnd || text[position] != ':') throw Error("expected ':'");
                    position++;
                    SkipWhitespace();
                    result.Add(key, ReadValue(depth));
                    SkipWhitespace();
                    if (AtEnd) throw Error("unterminated object");
                    if (text[position] == ',') { position++; continue; }
                    if (text[position] == '}') { position++; return result; }
                    throw Error("expected ',' or '}'");
                }
            }

            List<object> ReadArray(int depth)
            {
                if (depth > MaxDepth) throw Error("nested deeper than " + MaxDepth);
                var result = new List<object>();
                position++;  // [
                SkipWhitespace();
                if (!AtEnd && text[position] == ']') { position++; return result; }
                while (true)
                {
                    SkipWhitespace();
                    result.Add(ReadValue(depth));
                    SkipWhitespace();
                    if (AtEnd) throw Error("unterminated array");
                    if (text[position] == ',') { position++; continue; }
                    if (text[position] == ']') { position++; return result; }
                    throw Error("expected ',' or ']'");
                }
            }

            string ReadString()
            {
                var builder = new StringBuilder();
                position++;  // opening quote
                while (true)
                {
                    if (AtEnd) throw Error("unterminated string");
                    char c = text[position++];
                    if (c == '"') return builder.ToString();
                    if (c < 0x20) { position--; throw Error("control character in a string"); }
                    if (c != '\\') { builder.Append(c); continue; }
                    if (AtEnd) throw Error("unterminated string");
                    char escape = text[position++];
                    switch (escape)
                    {
                        case '"': builder.Append('"'); break;
                        case '\\': builder.Append('\\'); break;
                        case '/': builder.Append('/'); break;
                        case 'b': builder.Append('\b'); break;
                        case 'f': builder.Append('\f'); break;
                        case 'n': builder.Append('\n'); break;
                        case 'r': builder.Append('\r'); break;
                        case 't': builder.Append('\t'); break;
                        case 'u':
                            if (position + 4 > text.Length) throw Error("incomplete \\u escape");
                            int code;
                            if (!int.TryParse(text.Substring(position, 4), NumberStyles.AllowHexSpecifier,
                                              CultureInfo.InvariantCulture, out code))
                                throw Error("invalid \\u escape");
                            position += 4;
                            builder.Append((char)code);
                            break;
                        default:
                            position--;
                            throw Error("invalid escape '\\" + escape + "'");
                    }
                }
            }

            JsonNumber ReadNumber()
            {
                int start = position;
                if (text[position] == '-') position++;
                if (AtEnd) throw Error("expected a digit");
                if (text[position] == '0')
                {
                    position++;
                }
                else if (text[position] >= '1' && text[position] <= '9')
                {
                    while (!AtEnd && text[position] >= '0' && text[position] <= '9') position++;
                }
                else
                {
                    throw Error("expected a digit");
                }
                if (!AtEnd && text[position] == '.')
                {
                    position++;
                    if (AtEnd || text[position] < '0' || text[position] > '9') throw Error("expected a digit after '.'");
                    while (!AtEnd && text[position] >= '0' && text[position] <= '9') position++;
                }
                if (!AtEnd && (text[position] == 'e' || text[position] == 'E'))
                {
                    position++;
                    if (!AtEnd && (text[position] == '+' || text[position] == '-')) position++;
                    if (AtEnd || text[position] < '0' || text[position] > '9') throw Error("expected a digit in the exponent");
                    while (!AtEnd && text[position] >= '0' && text[position] <= '9') position++;
                }
                string literal = text.Substring(start, position - start);
                double value;
                try
                {
                    value = double.Parse(literal, NumberStyles.Float, CultureInfo.InvariantCulture);
                }
                catch (OverflowException)  // .NET Framework throws where .NET Core and Python give infinity
                {
                    value = literal[0] == '-' ? double.NegativeInfinity : double.PositiveInfinity;
                }
                return new JsonNumber(literal, value);
            }
        }
    }
}
