pub mod closed_form;
