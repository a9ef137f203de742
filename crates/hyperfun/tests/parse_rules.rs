//! Grammar rules: precedence, conditions, structure, checks and recovery.

use microfrep_hyperfun::ast::*;
use microfrep_hyperfun::{parse, Diagnostics};

fn model(body: &str) -> String {
    format!("my_model(x[3], a[2]) {{ {body} }}")
}

fn ok(src: &str) -> Program {
    parse(src, "t.hf").unwrap_or_else(|d| panic!("{}", d.render(src)))
}

fn err(src: &str) -> Diagnostics {
    parse(src, "t.hf")
        .err()
        .unwrap_or_else(|| panic!("accepted: {src}"))
}

/// The result expression in a compact prefix form.
fn show(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Num(v) => format!("{v}"),
        ExprKind::Var(n) => n.clone(),
        ExprKind::Index(n, i) => format!("{n}[{}]", show(i)),
        ExprKind::Unary(op, a) => format!("({op:?} {})", show(a)),
        ExprKind::Binary(op, a, b) => format!("({op:?} {} {})", show(a), show(b)),
        ExprKind::Call(n, args) => {
            let a: Vec<_> = args.iter().map(show).collect();
            format!("{n}({})", a.join(","))
        }
    }
}

fn result(expr: &str) -> String {
    show(&ok(&model(&format!("my_model = {expr};"))).objects[0].result)
}

#[test]
fn precedence_follows_hyperfun() {
    assert_eq!(result("1 + 2 | 3"), "(Union (Add 1 2) 3)");
    assert_eq!(result("x[1] | x[2] * 2"), "(Union x[1] (Mul x[2] 2))");
    assert_eq!(result("-x[1]^2"), "(Pow (Neg x[1]) 2)");
    assert_eq!(result("~x[1]^2"), "(Pow (Complement x[1]) 2)");
    assert_eq!(result("2^3^2"), "(Pow (Pow 2 3) 2)");
    assert_eq!(result("2^-1"), "(Pow 2 (Neg 1))");
    assert_eq!(
        result("x[3] \\ x[1] @ x[2]"),
        "(Product (Subtraction x[3] x[1]) x[2])"
    );
    assert_eq!(result("x[1] - -1"), "(Sub x[1] (Neg 1))");
    assert_eq!(result("HFSphere(X, a, 1)"), "hfsphere(x,a,1)");
}

#[test]
fn comment_swallows_double_minus() {
    let d = err(&model("y = 3; my_model = y--1;\n"));
    assert_eq!(d.message, "Semicolon expected");
}

#[test]
fn positions_of_operators_and_calls() {
    let p = ok("my_model(x[3], a[1]) {\n  my_model = sqrt(x[1]) ^ 2;\n}");
    let r = &p.objects[0].result;
    assert_eq!(r.pos, Pos { line: 2, col: 25 });
    let ExprKind::Binary(_, call, _) = &r.kind else {
        panic!()
    };
    assert_eq!(call.pos, Pos { line: 2, col: 14 });
}

#[test]
fn conditions_group_left_to_right() {
    let p = ok(&model(
        "r = 0; if x[1] > 0 or x[2] > 0 and not x[3] then r = 1; endif; my_model = r;",
    ));
    let Stmt::If { cond, .. } = &p.objects[0].body[1] else {
        panic!()
    };
    assert!(
        matches!(cond, Cond::And(l, r) if matches!(**l, Cond::Or(..)) && matches!(**r, Cond::Not(_)))
    );
    // A parenthesis at the start of an operand opens a condition.
    ok(&model(
        "r = 0; if (x[1] + 1) > 0 then r = 1; endif; my_model = r;",
    ));
    let d = err(&model(
        "r = 0; if (x[1] + 1) * 2 > 0 then r = 1; endif; my_model = r;",
    ));
    assert_eq!(d.message, "Reserved word \"then\" expected");
    err(&model("y = 2 < 3; my_model = y;"));
}

#[test]
fn statements_and_arrays() {
    let p = ok(&model(
        "array v[3], w[1]; v = [1, -2, +3]; w[1] = 2; s[1] = 1; s = [4]; i = 1;\
         while i < 3 loop i = i + 1; endloop; if i = 3 then else endif; my_model = v[i] + w[1];",
    ));
    let o = &p.objects[0];
    assert_eq!(o.arrays.len(), 2);
    assert_eq!((o.x_size, o.a_size, o.s_size), (3, 2, 1));
    assert!(matches!(&o.body[0], Stmt::AssignArray { values, .. } if *values == [1.0, -2.0, 3.0]));
    assert_eq!(o.body.len(), 7);
    assert_eq!(
        err(&model("array v[3]; v = [1, 2]; my_model = 1;")).message,
        "Comma expected"
    );
    assert_eq!(
        err(&model("array v[1]; v = [1, 2]; my_model = 1;")).message,
        "Right bracket expected"
    );
    assert_eq!(
        err(&model("y = 1; array v[3]; my_model = 1;")).message,
        "Body name expected"
    );
    assert_eq!(
        err(&model("x[1] = 2; my_model = 1;")).message,
        "Body name expected"
    );
    assert_eq!(
        err(&model("sin = 2; my_model = 1;")).message,
        "Body name expected"
    );
    assert_eq!(
        err(&model(";; my_model = 1;")).message,
        "Body name expected"
    );
    assert_eq!(
        err(&model("array v[0.4]; my_model = 1;")).message,
        "Array size must be greater zero"
    );
    // Sizes are rounded half up.
    assert_eq!(ok("m(x[2.5], a[1], s[3]) { m = 1; }").objects[0].x_size, 3);
}

#[test]
fn unassigned_names_and_objects() {
    let d = err(&model("my_model = zz + 1;"));
    assert_eq!(
        d.message,
        "Unassigned identificator used in expression: 'zz' is not a variable assigned before \
         this point"
    );
    let d = err(&model("r = 1; my_model = hfSpher(x, x, rr);"));
    assert_eq!(
        d.message,
        "Unassigned identificator used in expression: 'hfspher' is not a known function or an \
         object defined above (did you mean hfSphere?)"
    );
    let d = err(&model("radius = 1; my_model = radiu;"));
    assert!(
        d.message.ends_with("(did you mean radius?)"),
        "{}",
        d.message
    );
    // Assignment in an untaken branch still counts (textual order).
    ok(&model("if x[1] > 0 then y = 1; endif; my_model = y;"));
    err(&model(
        "if x[1] > 0 then my_model = y; y = 1; endif; my_model = 1;",
    ));
    ok("h(x[3], a[2]) { h = x[1]; } my_model(x[3], a[2]) { my_model = h(x, a) | H(x, a, s); }");
    let d = err("h(x[3], a[2]) { h = 1; } h(x[3], a[2]) { h = 2; }");
    assert_eq!(d.message, "Body name is not unique");
    let d = err("h(x[3], a[2], s[2]) { h = 1; } my_model(x[3], a[2]) { my_model = h(x, a); }");
    assert_eq!(d.message, "Wrong number of items in array");
    let d = err(&model("my_model = my_model;"));
    assert_eq!(
        d.message,
        "Unassigned identificator used in expression: 'my_model' is the object being defined; \
         it cannot use its own value"
    );
}

#[test]
fn calls_check_arity_and_array_arguments() {
    assert_eq!(
        err(&model("my_model = sqrt(1, 2);")).message,
        "Right parenthes expected: too many arguments to sqrt: expected 1, got 2"
    );
    assert_eq!(
        err(&model("my_model = hfSphere(x, x, 1, (2, 3), 4);")).message,
        "Right parenthes expected: too many arguments to hfSphere: expected 3, got 5"
    );
    assert_eq!(
        err(&model("my_model = max(1);")).message,
        "Comma expected: too few arguments to max: expected 2, got 1"
    );
    assert_eq!(
        err(&model("my_model = max(1 2);")).message,
        "Comma expected"
    );
    let d = err(&model("my_model = hfSphere(x, 2, 1);"));
    assert_eq!(
        (d.message.as_str(), d.pos.col),
        (
            "Error in argument in function call: argument 2 of hfSphere must be the name of an \
             array (x, a, s or a declared array)",
            47
        )
    );
    let d = err("h(x[3], a[2]) { h = 1; } my_model(x[3], a[2]) { my_model = h(x, a, s, x); }");
    assert!(d
        .message
        .starts_with("Right parenthes expected: too many arguments to object 'h'"));
    assert_eq!(
        err(&model("my_model = - - 1;")).message,
        "Second unary minus is not allowed"
    );
    assert_eq!(
        err(&model("my_model = 1 xor 2;")).message,
        "Semicolon expected"
    );
}

#[test]
fn all_recoverable_errors_are_reported() {
    let src = "my_model(x[3], a[1]) {\n  y = 1 +;\n  z = q;\n  if x[1] > then w = 1; endif;\n  my_model = y + z + w;\n}\n";
    let d = err(src);
    let at: Vec<_> = d
        .errors()
        .map(|e| (e.pos.line, e.message.as_str()))
        .collect();
    assert_eq!(
        at,
        [
            (2, "Expression expected"),
            (
                3,
                "Unassigned identificator used in expression: 'q' is not a variable assigned \
                 before this point"
            ),
            (4, "Expression expected"),
        ]
    );
    let text = d.render(src);
    assert!(
        text.starts_with("t.hf:2:10: error: Expression expected\n    y = 1 +;\n           ^\n"),
        "{text}"
    );
}

#[test]
fn structure_errors() {
    assert_eq!(err("").message, "Body name expected");
    assert_eq!(
        err(&model("my_model = 1; y = 2; my_model = y;")).message,
        "Right brace expected"
    );
    assert_eq!(
        err("m(x[3], a[1]) { m = 1; } ;").message,
        "Body name expected"
    );
    assert_eq!(err("m(y[3], a[1]) { m = 1; }").message, "\"X\" expected");
    assert_eq!(err("m(x[3] a[1]) { m = 1; }").message, "Comma expected");
    let d = err(&model(
        "if x[1] > 0 then my_model = 1; endif; my_model = 0;",
    ));
    assert_eq!(d.message, "Reserved words \"else\" or \"endif\" expected");
    let d = err(&model("while 1 loop y = 1; my_model = 0;"));
    assert_eq!(d.message, "Reserved word \"endloop\" expected");
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let deep = format!("{}1{}", "(".repeat(5000), ")".repeat(5000));
    let d = err(&model(&format!("my_model = {deep};")));
    assert_eq!(d.message, "Expression is nested too deeply");
}
