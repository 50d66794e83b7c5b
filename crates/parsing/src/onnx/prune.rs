//! [`without_outputs`]: an ONNX model with some graph outputs and the nodes only they need
//! removed, edited in protobuf wire format (no ONNX library): ONNX Runtime computes every
//! node of a graph whatever outputs a run asks for, so a run that does not need an output
//! is cheaper on a graph without it.

use std::collections::HashSet;

/// `ModelProto.graph`, `GraphProto.node`, `GraphProto.output`, `NodeProto.input`,
/// `NodeProto.output`, `ValueInfoProto.name` (onnx.proto field numbers).
const MODEL_GRAPH: u64 = 7;
const GRAPH_NODE: u64 = 1;
const GRAPH_OUTPUT: u64 = 12;
const NODE_INPUT: u64 = 1;
const NODE_OUTPUT: u64 = 2;
const VALUE_INFO_NAME: u64 = 1;
/// Wire types: varint, 64-bit, length-delimited, 32-bit.
const VARINT: u64 = 0;
const FIXED64: u64 = 1;
const LEN: u64 = 2;
const FIXED32: u64 = 5;

/// One field of a protobuf message: its number, its payload when length-delimited, and
/// its whole encoding (key included).
struct Field<'a> {
    number: u64,
    payload: Option<&'a [u8]>,
    raw: &'a [u8],
}

fn read_varint(b: &[u8], i: &mut usize) -> Option<u64> {
    let mut value = 0u64;
    for shift in (0..64).step_by(7) {
        let byte = *b.get(*i)?;
        *i += 1;
        value |= u64::from(byte & 0x7f) << shift;
        if byte < 0x80 {
            return Some(value);
        }
    }
    None
}

fn write_varint(mut value: u64, out: &mut Vec<u8>) {
    loop {
        let byte = (value & 0x7f) as u8;
        value >>= 7;
        if value == 0 {
            out.push(byte);
            return;
        }
        out.push(byte | 0x80);
    }
}

/// The fields of a message, `None` when the bytes are not a well-formed message (or use
/// the deprecated group wire types).
fn fields(b: &[u8]) -> Option<Vec<Field<'_>>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        let key = read_varint(b, &mut i)?;
        let payload = match key & 7 {
            VARINT => {
                read_varint(b, &mut i)?;
                None
            }
            FIXED64 => {
                i = i.checked_add(8).filter(|&e| e <= b.len())?;
                None
            }
            FIXED32 => {
                i = i.checked_add(4).filter(|&e| e <= b.len())?;
                None
            }
            LEN => {
                let n = usize::try_from(read_varint(b, &mut i)?).ok()?;
                let end = i.checked_add(n).filter(|&e| e <= b.len())?;
                let payload = &b[i..end];
                i = end;
                Some(payload)
            }
            _ => return None,
        };
        out.push(Field {
            number: key >> 3,
            payload,
            raw: &b[start..i],
        });
    }
    Some(out)
}

/// The UTF-8 strings of field `number` of a message (`None`: malformed).
fn strings(message: &[u8], number: u64) -> Option<Vec<&str>> {
    fields(message)?
        .into_iter()
        .filter(|f| f.number == number)
        .map(|f| f.payload.and_then(|p| std::str::from_utf8(p).ok()))
        .collect()
}

/// `model` (ONNX `ModelProto` bytes) without the graph outputs named in `drop` and
/// without every node that no remaining output needs (its other fields, initializers
/// included, as they were: ONNX Runtime drops unused initializers itself). `None` when the
/// bytes are not an ONNX model or an output in `drop` is not one of the graph's.
pub(crate) fn without_outputs(model: &[u8], drop: &[&str]) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(model.len());
    let mut found = false;
    for field in fields(model)? {
        let (MODEL_GRAPH, Some(graph)) = (field.number, field.payload) else {
            out.extend_from_slice(field.raw);
            continue;
        };
        found = true;
        let graph_fields = fields(graph)?;
        let mut outputs = Vec::new();
        let mut nodes = Vec::new();
        for f in &graph_fields {
            match (f.number, f.payload) {
                (GRAPH_OUTPUT, Some(p)) => outputs.push(*strings(p, VALUE_INFO_NAME)?.first()?),
                (GRAPH_NODE, Some(p)) => {
                    nodes.push((strings(p, NODE_INPUT)?, strings(p, NODE_OUTPUT)?))
                }
                _ => {}
            }
        }
        if !drop.iter().all(|d| outputs.contains(d)) {
            return None;
        }
        // Nodes are in topological order (ONNX requires it): walking them backwards, a
        // node is kept when one of its outputs is a kept graph output or a kept node's input.
        let mut needed: HashSet<&str> = outputs
            .iter()
            .copied()
            .filter(|o| !drop.contains(o))
            .collect();
        let mut keep = vec![false; nodes.len()];
        for (k, (inputs, node_outputs)) in nodes.iter().enumerate().rev() {
            if node_outputs.iter().any(|o| needed.contains(o)) {
                keep[k] = true;
                needed.extend(inputs.iter().copied());
            }
        }
        let mut new_graph = Vec::with_capacity(graph.len());
        let mut node = 0;
        for f in &graph_fields {
            match (f.number, f.payload) {
                (GRAPH_NODE, Some(_)) => {
                    if keep[node] {
                        new_graph.extend_from_slice(f.raw);
                    }
                    node += 1;
                }
                (GRAPH_OUTPUT, Some(p)) if drop.contains(strings(p, VALUE_INFO_NAME)?.first()?) => {
                }
                _ => new_graph.extend_from_slice(f.raw),
            }
        }
        write_varint(MODEL_GRAPH << 3 | LEN, &mut out);
        write_varint(new_graph.len() as u64, &mut out);
        out.extend_from_slice(&new_graph);
    }
    found.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A length-delimited field.
    fn ld(number: u64, payload: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        write_varint(number << 3 | LEN, &mut out);
        write_varint(payload.len() as u64, &mut out);
        out.extend_from_slice(payload);
        out
    }

    fn node(inputs: &[&str], outputs: &[&str]) -> Vec<u8> {
        let mut n = Vec::new();
        for i in inputs {
            n.extend(ld(NODE_INPUT, i.as_bytes()));
        }
        for o in outputs {
            n.extend(ld(NODE_OUTPUT, o.as_bytes()));
        }
        ld(GRAPH_NODE, &n)
    }

    /// x → a → (y, b); b → z; graph outputs y and z; a varint field (ir_version) before
    /// the graph stays.
    fn model() -> Vec<u8> {
        let mut g = Vec::new();
        g.extend(node(&["x"], &["a"]));
        g.extend(node(&["a"], &["y"]));
        g.extend(node(&["a"], &["b"]));
        g.extend(node(&["b"], &["z"]));
        g.extend(ld(GRAPH_OUTPUT, &ld(VALUE_INFO_NAME, b"y")));
        g.extend(ld(GRAPH_OUTPUT, &ld(VALUE_INFO_NAME, b"z")));
        let mut m = vec![0x08, 0x07]; // ir_version = 7
        m.extend(ld(MODEL_GRAPH, &g));
        m
    }

    type Nodes = Vec<(Vec<String>, Vec<String>)>;

    fn graph_of(model: &[u8]) -> (Nodes, Vec<String>) {
        let f = fields(model).expect("a message");
        assert_eq!(f[0].raw, [0x08, 0x07], "fields before the graph stay");
        let graph = f[1].payload.expect("the graph");
        let owned = |v: Vec<&str>| v.into_iter().map(String::from).collect::<Vec<_>>();
        let mut nodes = Vec::new();
        let mut outputs = Vec::new();
        for g in fields(graph).expect("a graph") {
            let p = g.payload.expect("length-delimited");
            match g.number {
                GRAPH_NODE => nodes.push((
                    owned(strings(p, NODE_INPUT).expect("inputs")),
                    owned(strings(p, NODE_OUTPUT).expect("outputs")),
                )),
                GRAPH_OUTPUT => outputs.extend(owned(strings(p, VALUE_INFO_NAME).expect("name"))),
                _ => {}
            }
        }
        (nodes, outputs)
    }

    #[test]
    fn dropping_an_output_drops_the_nodes_only_it_needs() {
        let m = model();
        let (nodes, outputs) = graph_of(&without_outputs(&m, &["z"]).expect("prunable"));
        assert_eq!(outputs, ["y"]);
        let produced: Vec<&str> = nodes
            .iter()
            .flat_map(|n| n.1.iter().map(String::as_str))
            .collect();
        assert_eq!(produced, ["a", "y"], "b and z are only z's");
        let (nodes, outputs) = graph_of(&without_outputs(&m, &["y"]).expect("prunable"));
        assert_eq!(outputs, ["z"]);
        assert_eq!(nodes.len(), 3, "a stays: b needs it");
        assert_eq!(without_outputs(&m, &[]).expect("nothing to drop"), m);
        assert!(without_outputs(&m, &["w"]).is_none(), "no such output");
        assert!(
            without_outputs(&[0xff, 0xff], &["y"]).is_none(),
            "not a model"
        );
    }
}
