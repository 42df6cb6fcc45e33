#[path = "../../../tests/core_props.rs"] mod core_props;
